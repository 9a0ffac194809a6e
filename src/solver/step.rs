//! One load step: the matrix pattern of the step, the predictor, the Newton attempts (the stick
//! predictor, full steps, the fallback line search), the Uzawa loop, and then either the step's
//! outputs or a cut (module docs of [`super`]).

use std::cell::Cell;
use std::time::Instant;

use mpi::collective::{CommunicatorCollectives, SystemOperation};

use crate::error::{print_warning, Error, Result};
use crate::interrupt;
use crate::io::output::StepRecord;
use crate::model::Augmented;
use crate::petsc::{CallbackError, SnesOutcome, UpdateCheck, Vector};

use super::assembly;
use super::collective::{any_rank, sum_over_ranks};
use super::cut::{cut_limit, describe, what_to_change};
use super::evaluation::{Evaluation, Verdict};
use super::pattern_update::{hold_iterate, PATTERN_PHASE};
use super::predictor::{predict, NewtonTangent};
use super::results::StepRow;
use super::rigid_motion;
use super::summary::{not_started, retries_note, Load};
use super::{Run, FULL_STEP_CYCLE_PROGRESS, FULL_STEP_ITERATIONS, STICK_PREDICTOR_ITERATIONS};

/// What became of a step.
pub(super) enum StepEnd {
    /// It converged (or was accepted unconverged) and its outputs are written.
    Finished,
    /// It failed and was cut: the same step again, halved.
    Cut,
    /// It failed with no cut left: the run ends.
    GaveUp,
    /// A signal stopped the run.
    Stopped,
}

/// What one Newton iteration of the bilateral problem did.
enum BilateralNewton {
    /// None: the iterate already met the tolerances.
    AtTolerance,
    /// It failed before its update was accepted (a failed linear solve, an inverted element).
    Failed,
    /// The law's residual `|F(x; t)|` at its result, `None` where some rank cannot evaluate
    /// it.
    Reached(Option<f64>),
}

/// What a step's solves counted.
#[derive(Default)]
struct Counted {
    augmentations: usize,
    /// Newton and linear iterations of every solve of the step (failed attempts included).
    newton: usize,
    linear: usize,
    /// The step's first solve started with the fallback line search.
    led: bool,
    /// The step began with a bilateral iteration, kept (`true`) or undone.
    bilateral: Option<bool>,
    /// Tangent entries added outside the matrix pattern, over all ranks.
    outside_pattern: u64,
    /// Newton iterates at which the matrix pattern grew (`hold_iterate`).
    pattern_grown: u64,
    /// Newton updates solved a second time (`newton.hold_closing`), and those the second
    /// update replaced.
    second_solves: usize,
    second_solves_kept: usize,
}

impl Counted {
    /// Counts the iterations of `solve`.
    fn add(&mut self, solve: &SnesOutcome) {
        self.newton += solve.iterations;
        self.linear += solve.linear_iterations;
        self.second_solves += solve.second_solves;
        self.second_solves_kept += solve.second_solves_kept;
    }
}

/// The solves of one step.
pub(super) struct Solved {
    /// The last solve's outcome.
    outcome: SnesOutcome,
    counted: Counted,
}

/// Seconds of a step's solves (the predictor's included): their evaluations, and in all.
#[derive(Clone, Copy)]
struct StepSeconds {
    assembly: f64,
    total: f64,
}

impl Run<'_> {
    /// One load step from the load of the last finished step.
    pub(super) fn step(&mut self) -> Result<StepEnd> {
        if self.stop_requested().is_some() {
            return Ok(StepEnd::Stopped);
        }
        let (t, t_new) = (self.state.t, self.state.next_load());
        if t_new <= t {
            // (The case file's bound on steps.max_cuts keeps steps far above this.)
            return Err(Error::Solve(format!(
                "the load step {:.3e} no longer advances the load {} in floating point",
                self.state.dt,
                Load(t)
            )));
        }
        self.linear.x.copy_to(&mut self.linear.x_prev)?;
        let lead_at_start = self.state.lead_with_fallback;
        self.grow_pattern(t)?;
        self.model.save();
        {
            let mut ev = self.cx.evaluator.borrow_mut();
            (ev.assembly_seconds, ev.outside_pattern) = (0.0, 0);
            (ev.pattern_seconds, ev.pattern_grown) = (0.0, 0);
        }
        // The contributions' timed work of this step's evaluations, the predictor's included.
        let timed_before = self.model.phase_seconds();
        let started = Instant::now();
        // The seconds of the pattern's renewal at the predicted end of the step: in its own
        // phase (as the step start's update is), not the solve's. A prediction that left the
        // state where it was (its solve failed) keeps the pattern as it is.
        let mut pattern_seconds = 0.0;
        if self.cx.scene.predictor && self.predict(t, t_new)? {
            pattern_seconds = self.renew_pattern(t, t_new)?;
        }
        self.cx.evaluator.borrow_mut().t = t_new;
        self.linear.snes.rebuild_multigrid();
        let solve_stage = self.phases.push("solve")?;
        let mut solved = self.solve_step(t_new)?;
        self.linear.snes.force_iteration(false)?;
        drop(solve_stage);
        self.state.counts.newton += solved.counted.newton;
        let seconds = self.account_time(started, pattern_seconds, &timed_before);
        solved.counted.outside_pattern = self.step_outside_pattern();
        solved.counted.pattern_grown = self.cx.evaluator.borrow().pattern_grown;
        self.check_null_pivots(t_new)?;
        if solved.outcome.converged {
            return self.finish_step(&solved, t_new, seconds, false);
        }
        if self.state.stop.get().is_some() {
            // The run ends at the last finished step, as a failed one does (its checkpoint
            // holds the state this step started from).
            self.restore()?;
            self.state.lead_with_fallback = lead_at_start;
            return Ok(StepEnd::Stopped);
        }
        if self.accepts_unconverged(&solved.outcome)? {
            return self.finish_step(&solved, t_new, seconds, true);
        }
        self.cut(&solved, t_new)
    }

    /// The tangent entries this step added outside the matrix pattern, over the ranks
    /// (*collective*).
    fn step_outside_pattern(&self) -> u64 {
        let mine = self.cx.evaluator.borrow().outside_pattern;
        sum_over_ranks(&self.cx.world, mine)
    }

    /// The load-step predictor from `t` to `t_new` (`steps.predictor`); true when it moved the
    /// iterate.
    fn predict(&mut self, t: f64, t_new: f64) -> Result<bool> {
        let reuse = self.cx.scene.predictor_reuses_newton_tangent
            && self.linear.tangent.newton == NewtonTangent::OfLastConvergedStep;
        let ev = Evaluation {
            cx: &self.cx,
            model: &self.model,
        };
        let l = &mut self.linear;
        predict(
            &ev,
            (&mut l.x, &mut l.jac, &mut l.snes),
            (t, t_new),
            &mut l.tangent,
            reuse,
        )
    }

    /// The step's solves: the bilateral iteration and the stick predictor, then attempts and Uzawa
    /// augmentations until the augmented contributions meet their tolerances. Where they take
    /// updates, the solves stop at `newton.augmented_rtol` until the tolerances are met, and a
    /// last solve meets `newton.rtol` (docs/theory.md section 4).
    fn solve_step(&mut self, t_new: f64) -> Result<Solved> {
        let mut counted = Counted::default();
        if self.cx.scene.bilateral_iteration {
            self.bilateral_iteration(&mut counted, t_new)?;
        }
        if self.cx.scene.stick_predictor && self.model.is_frictional() {
            self.stick_predictor(&mut counted)?;
        }
        let augmented = self.model.is_augmented();
        let mut loose = self.model.takes_uzawa_updates();
        let mut first_of_step = true;
        loop {
            let rtol = if loose { self.loosen()? } else { None };
            let outcome = self.attempt(&mut counted, first_of_step);
            if let Some(rtol) = rtol {
                self.linear.snes.set_relative_tolerance(rtol)?;
            }
            let outcome = outcome?;
            first_of_step = false;
            counted.add(&outcome);
            if !outcome.converged || !augmented {
                return Ok(Solved { outcome, counted });
            }
            let last = rtol.is_none();
            if self.augmented(&mut counted, t_new, last)? {
                // The new multipliers change the residual by little once the gap is small:
                // still take one Newton step, so that the displacements follow.
                self.linear.snes.force_iteration(true)?;
                loose = true;
            } else if last {
                return Ok(Solved { outcome, counted });
            } else {
                // Within the tolerances after a loose solve: the step's last solve meets
                // `newton.rtol`, and the multipliers are checked again at its result.
                self.linear.snes.force_iteration(false)?;
                loose = false;
            }
        }
    }

    /// Sets the Newton solves' relative tolerance to `newton.augmented_rtol` when that is the
    /// looser one; returns the tolerance to restore, if so.
    fn loosen(&mut self) -> Result<Option<f64>> {
        let loose = self.cx.scene.newton.augmented_rtol;
        let rtol = self.linear.snes.set_relative_tolerance(loose)?;
        if rtol >= loose {
            self.linear.snes.set_relative_tolerance(rtol)?;
            return Ok(None);
        }
        Ok(Some(rtol))
    }

    /// The bilateral iteration (`contact::frictional`, "Bilateral iteration"): one Newton
    /// iteration in which every node with a normal multiplier (pressed at the last converged
    /// step) is held bilaterally, and a second one from its result when the first raised the
    /// law's residual. It is kept when the law's residual at its result is below the residual
    /// at the step's start, and undone otherwise, the step's first solve then led by the
    /// fallback line search (not in a cut step); its iterations count either way. Nothing
    /// when no rank has such a node (*collective*).
    fn bilateral_iteration(&mut self, counted: &mut Counted, t: f64) -> Result<()> {
        if !any_rank(&self.cx.world, self.model.has_bilateral_nodes()) {
            return Ok(());
        }
        let before = self.residual_norm(t)?;
        let l = &mut self.linear;
        l.x.copy_to(&mut l.x_guess)?;
        // The law's residual after each iteration, `None` after a failed one (which may have
        // moved the iterate: undone).
        let mut reached = Vec::with_capacity(2);
        match self.bilateral_newton_iteration(counted, t)? {
            // The start already met the tolerances: nothing was tried.
            BilateralNewton::AtTolerance => return Ok(()),
            BilateralNewton::Failed => reached.push(None),
            BilateralNewton::Reached(first) => {
                reached.push(first);
                if matches!((before, first), (Some(b), Some(a)) if a >= b) {
                    // From a start where the predictor opened every pressed node, one Newton
                    // iteration of the bilateral problem may not yet lower the law's
                    // residual; its result, where the nodes press again, is a better start
                    // for a second (docs/theory.md, "Bilateral iteration").
                    match self.bilateral_newton_iteration(counted, t)? {
                        BilateralNewton::AtTolerance => {}
                        BilateralNewton::Failed => reached.push(None),
                        BilateralNewton::Reached(second) => reached.push(second),
                    }
                }
            }
        }
        let after = reached[reached.len() - 1];
        let kept = matches!((before, after), (Some(b), Some(a)) if a < b);
        if !kept {
            let l = &mut self.linear;
            l.x_guess.copy_to(&mut l.x)?;
            // Nodes that truly lift off, or a bilateral step that inverted an element: the
            // step is one whose full Newton steps fail like the bilateral one. (A cut step
            // tries full steps first, as after a failed led solve.)
            if self.fallback_line_search.is_some() && self.state.cuts_in_row == 0 {
                self.state.lead_with_fallback = true;
            }
        }
        counted.bilateral = Some(kept);
        if self.contact_monitor && self.cx.rank == 0 {
            let norm = |n: Option<f64>| n.map_or("-".to_string(), |n| format!("{n:.3e}"));
            let verdict = if kept { "kept" } else { "undone" };
            let path: Vec<String> = reached.into_iter().map(norm).collect();
            println!(
                "    bilateral iteration {verdict}: |F| {} -> {}",
                norm(before),
                path.join(" -> ")
            );
        }
        Ok(())
    }

    /// One Newton iteration of the bilateral problem from the current iterate (the iteration
    /// counts in `counted`).
    fn bilateral_newton_iteration(
        &mut self,
        counted: &mut Counted,
        t: f64,
    ) -> Result<BilateralNewton> {
        self.model.set_bilateral(true);
        let max_it = self.linear.snes.set_max_iterations(1)?;
        let solve = self.solve_once();
        self.model.set_bilateral(false);
        self.linear.snes.set_max_iterations(max_it)?;
        let solve = solve?;
        counted.add(&solve);
        Ok(match (solve.iterations, solve.converged) {
            (0, true) => BilateralNewton::AtTolerance,
            (0, false) => BilateralNewton::Failed,
            _ => BilateralNewton::Reached(self.residual_norm(t)?),
        })
    }

    /// `|F(x; t)|` at the current iterate, `None` where some rank cannot evaluate it
    /// (*collective*).
    fn residual_norm(&self, t: f64) -> Result<Option<f64>> {
        let ev = Evaluation {
            cx: &self.cx,
            model: &self.model,
        };
        ev.residual_at(&self.linear.x, t)?
            .map(|f| f.norm2())
            .transpose()
    }

    /// The stick predictor (see `contact::frictional`): solve with every pressed node
    /// sticking, then release the Coulomb law from there (or from the start, when it did not
    /// converge).
    fn stick_predictor(&mut self, counted: &mut Counted) -> Result<()> {
        let l = &mut self.linear;
        l.x.copy_to(&mut l.x_guess)?;
        self.model.set_stick_all(true);
        let max_it = self
            .linear
            .snes
            .set_max_iterations(STICK_PREDICTOR_ITERATIONS)?;
        let pre = self.solve_once();
        self.model.set_stick_all(false);
        self.linear.snes.set_max_iterations(max_it)?;
        let pre = pre?;
        counted.add(&pre);
        if !pre.converged {
            let l = &mut self.linear;
            l.x_guess.copy_to(&mut l.x)?;
        }
        Ok(())
    }

    /// One attempt at the step's solve: full Newton steps, and with frictional contact, when
    /// they do not converge within [`FULL_STEP_ITERATIONS`] (or they cycle:
    /// [`FULL_STEP_CYCLE_PROGRESS`]), the same solve from the same start with the
    /// fallback line search (the failed attempt's iterations go to `counted`).
    ///
    /// A step's first solve (`first_of_step`; the Uzawa augmentations' solves start close to
    /// their solution) starts with the fallback line search instead when the last step's first
    /// solve needed it ([`super::state::RunState::lead_with_fallback`]): in a steady slide
    /// every step's full steps fail alike. It keeps doing so while that line search shortens
    /// a step; once it takes full steps throughout, the next step tries full steps again.
    /// When the led solve fails, full steps get the second attempt from the same start (with
    /// every iteration the solve allows), and the step's later cuts try full steps first.
    fn attempt(&mut self, counted: &mut Counted, first_of_step: bool) -> Result<SnesOutcome> {
        let Some(line_search) = self.fallback_line_search else {
            return self.solve_once();
        };
        self.linear.x.copy_to(&mut self.linear.x_attempt)?;
        if first_of_step && self.state.lead_with_fallback {
            return self.led_attempt(counted, line_search);
        }
        let l = &mut self.linear;
        let max_it = l.snes.set_max_iterations(FULL_STEP_ITERATIONS)?;
        if max_it < FULL_STEP_ITERATIONS {
            l.snes.set_max_iterations(max_it)?;
        }
        l.snes.stop_on_cycling(Some(FULL_STEP_CYCLE_PROGRESS));
        let first = self.solve_once();
        self.linear.snes.stop_on_cycling(None);
        self.linear.snes.set_max_iterations(max_it)?;
        let first = first?;
        if first.converged || self.state.stop.get().is_some() {
            return Ok(first);
        }
        counted.add(&first);
        self.state.counts.fallbacks += 1;
        self.state.lead_with_fallback |= first_of_step;
        self.linear.x_attempt.copy_to(&mut self.linear.x)?;
        self.solve_with(line_search)
    }

    /// [`Run::attempt`] led by `line_search` from the start saved in `x_attempt`: full steps
    /// get the second attempt when it fails.
    fn led_attempt(&mut self, counted: &mut Counted, line_search: &str) -> Result<SnesOutcome> {
        counted.led = true;
        let led = self.solve_with(line_search)?;
        if led.converged || self.state.stop.get().is_some() {
            self.state.lead_with_fallback = led.shortened;
            return Ok(led);
        }
        counted.add(&led);
        self.state.lead_with_fallback = false;
        self.linear.x_attempt.copy_to(&mut self.linear.x)?;
        self.solve_once()
    }

    /// [`Run::solve_once`] with the line search `line_search`, then full steps again.
    fn solve_with(&mut self, line_search: &str) -> Result<SnesOutcome> {
        self.linear.snes.set_line_search(line_search)?;
        let outcome = self.solve_once();
        self.linear.snes.set_line_search("basic")?;
        outcome
    }

    /// One SNES solve of the current model from the current iterate (the closures borrow the
    /// model, so they are made afresh for every solve).
    fn solve_once(&mut self) -> Result<SnesOutcome> {
        if let Some(signal) = self.state.stop.get() {
            return Ok(not_started(signal));
        }
        let ev = Evaluation {
            cx: &self.cx,
            model: &self.model,
        };
        let assembly_stage = self.phases.stage("assembly");
        let (world, stop) = (&self.cx.world, &self.state.stop);
        // A second solve's tangent is of the held law: not reported.
        let resolving = Cell::new(false);
        let report = |verdict: Verdict| {
            if self.contact_monitor && verdict.is_ok() && !resolving.get() {
                let lines = self.model.iteration_report(world);
                if self.cx.rank == 0 {
                    lines.iter().for_each(|l| println!("{l}"));
                }
            }
            verdict
        };
        let mut residual = |x: &_, f: &mut _| -> Result<(), CallbackError> {
            let _stage = assembly_stage.map(|st| st.push()).transpose()?;
            ev.residual(x, f)?
        };
        let pattern_stage = self.phases.stage(PATTERN_PHASE);
        let pattern = &mut self.linear.pattern;
        let mut jacobian = |x: &_, j: &mut _| -> Result<(), CallbackError> {
            // Once per Newton iteration, before its costly part. As a domain error, SNES ends
            // the solve cleanly (not converged); the step loop stops on it.
            if let Some(signal) = interrupt::agreed(world) {
                stop.set(Some(signal));
                let name = interrupt::name(signal);
                return Err(CallbackError::Domain(format!("interrupted by {name}")));
            }
            {
                let _stage = pattern_stage.map(|st| st.push()).transpose()?;
                hold_iterate(&ev, pattern, x, j)?;
            }
            let _stage = assembly_stage.map(|st| st.push()).transpose()?;
            report(ev.jacobian(x, j)?)
        };
        let mut contact_updates = ContactUpdates {
            ev,
            monitor: self.contact_monitor,
            hold_closing: self.cx.scene.newton.hold_closing,
            resolving: &resolving,
            update: None,
        };
        let update_check = self
            .model
            .pattern_moves()
            .then_some(&mut contact_updates as &mut dyn UpdateCheck);
        let (snes, x, jac) = (
            &mut self.linear.snes,
            &mut self.linear.x,
            &mut self.linear.jac,
        );
        snes.solve_limited(x, jac, (&mut residual, &mut jacobian), update_check)
    }

    /// After a converged solve: one Uzawa step of the augmented contributions. Returns true
    /// when they updated their multipliers (solve again). A cap reached after a solve that is
    /// not the step's `last` (a loose one) is said after the last.
    fn augmented(&mut self, counted: &mut Counted, t_new: f64, last: bool) -> Result<bool> {
        let mut ev = self.cx.evaluator.borrow_mut();
        ev.load(self.cx.scene, &self.cx.dofs, &self.linear.x)?;
        let at = ev.state(self.cx.scene);
        let step = self
            .model
            .augment(&at, counted.augmentations, &self.cx.world);
        match step.outcome {
            Augmented::Converged => Ok(false),
            Augmented::CapReached if !last => Ok(false),
            Augmented::CapReached => {
                self.state.counts.uzawa_capped += 1;
                if self.cx.rank == 0 {
                    print_warning(format_args!(
                        "step {} (load {}): an interface is still above its Uzawa tolerances \
                         after uzawa_max = {} augmentations ({})",
                        self.state.step + 1,
                        Load(t_new),
                        counted.augmentations,
                        step.violation
                    ));
                }
                Ok(false)
            }
            Augmented::Updated => {
                counted.augmentations += 1;
                Ok(true)
            }
        }
    }

    /// Adds the step's evaluation and solve times to the phases; the contributions' timed
    /// parts of assembly apart (`timed_before`: their totals at the step's start);
    /// `pattern_seconds` since `started` belong to neither (the `pattern` phase has them).
    fn account_time(
        &mut self,
        started: Instant,
        pattern_seconds: f64,
        timed_before: &std::collections::BTreeMap<&'static str, f64>,
    ) -> StepSeconds {
        let (assembly, held) = {
            let ev = self.cx.evaluator.borrow();
            (ev.assembly_seconds, ev.pattern_seconds)
        };
        let total = started.elapsed().as_secs_f64() - pattern_seconds - held;
        self.phases.add(PATTERN_PHASE, held);
        self.phases.add("assembly", assembly);
        self.phases.add("solve", (total - assembly).max(0.0));
        let mut timed = 0.0;
        for (name, now) in self.model.phase_seconds() {
            let spent = now - timed_before.get(name).copied().unwrap_or(0.0);
            self.phases.add(name, spent);
            timed += spent;
        }
        self.phases
            .add("bulk_assembly", (assembly - timed).max(0.0));
        StepSeconds { assembly, total }
    }

    /// A singular tangent (the predictor's factorization counts: a linear scene may need no
    /// Newton step) ends the run: MUMPS's null pivots, or where the linear solver is not a
    /// MUMPS factorization, a body's rigid motion the tangent does not resist
    /// (`rigid_motion`). *Collective*.
    fn check_null_pivots(&self, t_new: f64) -> Result<()> {
        const TAIL: &str = "(constrain it: dirichlet or symmetry sets), or the input degrades \
                            the tangent (too low a quadrature_degree, an extreme penalty or load)";
        let load = Load(t_new);
        match self.linear.snes.null_pivots()? {
            Some(n) if n > 0 => Err(Error::Solve(format!(
                "the tangent stiffness is singular ({n} null pivot(s) at load {load}): a body \
                 can move rigidly {TAIL}"
            ))),
            Some(_) => Ok(()),
            // A tangent with inverted elements left out may be singular where the bodies are
            // held: that step is cut, as on the direct solve.
            None if !self.cx.evaluator.borrow().tangent_whole => Ok(()),
            None => {
                let bodies = &self.cx.scene.mesh.bodies;
                let free =
                    rigid_motion::free_bodies(&self.linear.jac, &self.linear.rigid_modes, bodies)?;
                let names: Vec<String> = free.iter().map(|b| format!("'{b}'")).collect();
                let who = match names.as_slice() {
                    [] => return Ok(()),
                    [one] => format!("body {one}"),
                    many => format!("bodies {}", many.join(", ")),
                };
                Err(Error::Solve(format!(
                    "the tangent stiffness is singular at load {load}: {who} can move rigidly \
                     {TAIL}"
                )))
            }
        }
    }

    /// Whether a step whose solve did not converge is accepted as it is
    /// (`steps.on_failure = "continue"`): no cut left, and a state Newton reached inside the
    /// domain (*collective*).
    fn accepts_unconverged(&self, outcome: &SnesOutcome) -> Result<bool> {
        let (state, scene) = (&self.state, self.cx.scene);
        Ok(cut_limit(
            state.cuts_in_row,
            scene.max_cuts,
            state.taken(),
            state.dt_min,
        )
        .is_some()
            && scene.continue_on_failure
            && outcome.domain_error.is_none()
            && self.linear.x.norm2()?.is_finite())
    }

    /// A step whose solve did not converge: back to the step's start, and the same step again
    /// at half the size, or the run gives up when no cut is left.
    fn cut(&mut self, solved: &Solved, t_new: f64) -> Result<StepEnd> {
        let outcome = &solved.outcome;
        let why = outcome
            .domain_error
            .clone()
            .unwrap_or_else(|| outcome.reason.to_string());
        let (state, max_cuts) = (&self.state, self.cx.scene.max_cuts);
        let taken = state.taken();
        let limit = cut_limit(state.cuts_in_row, max_cuts, taken, state.dt_min)
            .map(|limit| describe(&limit, taken, max_cuts));
        self.linear.tangent.newton = NewtonTangent::Other;
        self.state.cut();
        self.restore()?;
        self.say(format!(
            "  step {} load {:.6}: not converged ({why}) after {} Newton its{}; {}",
            self.state.step + 1,
            Load(t_new),
            outcome.iterations,
            pattern_note(&solved.counted),
            match &limit {
                Some(limit) => limit.clone(),
                None => format!("cut {}/{max_cuts}", self.state.cuts_in_row),
            }
        ));
        if let Some(limit) = limit {
            let advice = what_to_change(outcome.reason, outcome.domain_error.is_some());
            self.summary.message = Some(format!(
                "step {} (load {}) did not converge after {} cut(s), {limit}: {why}; {advice}",
                self.state.step + 1,
                Load(t_new),
                self.state.cuts_in_row - 1
            ));
            return Ok(StepEnd::GaveUp);
        }
        Ok(StepEnd::Cut)
    }

    /// Back to the state at the step's start.
    fn restore(&mut self) -> Result<()> {
        let l = &mut self.linear;
        l.x_prev.copy_to(&mut l.x)?;
        self.model.restore();
        Ok(())
    }

    /// A step that converged, or that is `accepted` unconverged: its outputs, its commit, its
    /// history row, the summary, and its progress line.
    fn finish_step(
        &mut self,
        solved: &Solved,
        t_new: f64,
        seconds: StepSeconds,
        accepted: bool,
    ) -> Result<StepEnd> {
        let outcome = &solved.outcome;
        // The factorization the solver holds now: the last Newton iteration's of the step's
        // final, converged solve when it took one (after the predictor's and any failed
        // attempt's), else another.
        self.linear.tangent.newton = if outcome.converged && outcome.iterations > 0 {
            NewtonTangent::OfLastConvergedStep
        } else {
            NewtonTangent::Other
        };
        self.state.advance(t_new);
        let output_started = Instant::now();
        let output_stage = self.phases.push("output")?;
        let residual = outcome.residual_history.last().copied().unwrap_or(0.0);
        self.write_step_outputs(solved, residual, seconds, output_started)?;
        drop(output_stage);
        self.phases
            .add("output", output_started.elapsed().as_secs_f64());
        if self.cx.rank == 0 {
            self.summary.timings = self.phases.timings();
            self.results.write_summary(&self.summary);
        }
        self.results.agree(&self.cx.world)?;
        // Reported once the step's files are written: a run stopped by its reader (a closed
        // stdout) has the step on disk.
        self.report_step(solved, residual, seconds, accepted);
        self.state.close_step();
        Ok(StepEnd::Finished)
    }

    /// The step's files and records: reactions, tracked sets, the VTU pieces (every
    /// `output.vtu_every` steps and the last), the commit of the model, the history row and
    /// the summary's step record (*collective*).
    fn write_step_outputs(
        &mut self,
        solved: &Solved,
        residual: f64,
        seconds: StepSeconds,
        output_started: Instant,
    ) -> Result<()> {
        let (step, t) = (self.state.step, self.state.t);
        let matrix_entries = self.matrix_entries()?;
        let mut ev = self.cx.evaluator.borrow_mut();
        ev.load(self.cx.scene, &self.cx.dofs, &self.linear.x)?;
        let at = ev.state(self.cx.scene);
        let nodal = assembly::nodal_forces(&self.model, &at)?;
        let reactions = self.results.reactions(&nodal, &self.cx.world);
        let tracked = self
            .results
            .tracked(self.cx.scene, &self.cx.dofs, at.u, &self.cx.world);
        let every = self.cx.scene.vtu_every;
        if every > 0 && (step % every == 0 || t >= 1.0) {
            let outputs = self.model.output(&at, &self.cx.world);
            let dofs = (self.cx.scene, &self.cx.dofs);
            self.results
                .write_step(dofs, &outputs, at.u, (step, t), &self.cx.world)?;
        }
        self.model.commit(&at, &self.cx.world);
        self.results.push_history(&StepRow {
            step,
            load: t,
            newton_its: solved.counted.newton,
            augmentations: solved.counted.augmentations,
            cuts: self.state.cuts_in_row,
            converged: solved.outcome.converged,
            linear_its: solved.counted.linear,
            residual,
            reactions: &reactions,
            u: at.u,
            tracked: &tracked,
            contributions: &self.model.history(),
            matrix_entries,
            seconds: [
                seconds.assembly,
                (seconds.total - seconds.assembly).max(0.0),
                output_started.elapsed().as_secs_f64(),
            ],
        });
        self.summary.steps.push(StepRecord {
            step,
            load: t,
            newton_its: solved.counted.newton,
            cut: self.state.cuts_in_row,
            converged: solved.outcome.converged,
            augmentations: solved.counted.augmentations,
        });
        Ok(())
    }

    /// The step's progress line (and the note of a step accepted unconverged).
    fn report_step(
        &mut self,
        solved: &Solved,
        residual: f64,
        seconds: StepSeconds,
        accepted: bool,
    ) {
        let (step, load) = (self.state.step, Load(self.state.t));
        if accepted {
            self.state.counts.unconverged += 1;
            self.say(format!(
                "  step {step} load {load:.6}: NOT converged ({}) after {} Newton its, |F| \
                 {residual:.3e}; accepted (steps.on_failure = \"continue\")",
                solved.outcome.reason, solved.counted.newton
            ));
        }
        let counts = &self.state.counts;
        let uzawa = match solved.counted.augmentations {
            0 => String::new(),
            n => format!(" ({n} Uzawa augmentations)"),
        };
        let floor = match self.linear.snes.round_off_floor() {
            (floor, true) => format!(" (below its round-off floor {floor:.1e})"),
            _ => String::new(),
        };
        let led = match (solved.counted.led, self.fallback_line_search) {
            (true, Some(line_search)) => format!(", started with {line_search}"),
            _ => String::new(),
        };
        let pattern = pattern_note(&solved.counted);
        let second = match (
            solved.counted.second_solves,
            solved.counted.second_solves_kept,
        ) {
            (0, _) => String::new(),
            (1, kept) => format!(", 1 Newton update solved again ({kept} kept)"),
            (n, kept) => format!(", {n} Newton updates solved again ({kept} kept)"),
        };
        let bilateral = match solved.counted.bilateral {
            Some(true) => ", bilateral",
            Some(false) => ", bilateral undone",
            None => "",
        };
        self.say(format!(
            "  step {step} load {load:.6}: {} Newton its{uzawa}, |F| {residual:.3e}{floor}, {} \
             linear its{bilateral}{second}{led}{}{pattern}, {:.2} s",
            solved.counted.newton,
            solved.counted.linear,
            retries_note(
                self.state.cuts_in_row,
                counts.fallbacks - counts.fallbacks_before,
                self.fallback_line_search
            ),
            seconds.total
        ));
    }
}

/// The check of every Newton update of a contact whose pattern moves. The update is kept
/// within the contact search's reach (`reach_fraction`). Where it carries contact nodes open
/// at the iterate through the other surface, it is solved a second time with those nodes held
/// pressed (`newton.hold_closing`; `contact::frictional`, "Nodes a Newton update closes").
struct ContactUpdates<'a> {
    ev: Evaluation<'a>,
    monitor: bool,
    hold_closing: bool,
    /// Set while the law holds them: the second solve's tangent is not reported.
    resolving: &'a Cell<bool>,
    /// The update as the last `limit` shortened it, gathered at every dof this rank touches
    /// (with `hold_closing`, for the `ask` that follows it).
    update: Option<Vec<f64>>,
}

impl UpdateCheck for ContactUpdates<'_> {
    fn limit(&mut self, x: &Vector, y: &Vector) -> Result<f64, CallbackError> {
        let mut du = self.ev.load_update(x, y)?;
        let local = self.ev.step_fraction(&du);
        let cx = self.ev.cx;
        let mut fraction = local;
        cx.world
            .all_reduce_into(&local, &mut fraction, SystemOperation::min());
        if fraction < 1.0 {
            self.say(format_args!(
                "Newton update shortened to {fraction:.3e} of it (contact search reach)"
            ));
        }
        if self.hold_closing {
            if fraction < 1.0 {
                du.iter_mut().for_each(|d| *d *= fraction);
            }
            self.update = Some(du);
        }
        Ok(fraction)
    }

    fn ask(&mut self, x: &Vector, y: &Vector) -> Result<bool, CallbackError> {
        if !self.hold_closing {
            return Ok(false);
        }
        let du = match self.update.take() {
            Some(du) => du,
            None => self.ev.load_update(x, y)?,
        };
        let closing = self.ev.hold_closing(&du);
        if closing.held == 0 {
            return Ok(false);
        }
        self.say(format_args!(
            "Newton update solved again, {} nodes held pressed (deepest {:.2e} h past closing)",
            closing.held, closing.deepest
        ));
        self.resolving.set(true);
        Ok(true)
    }

    fn release(&mut self) {
        self.ev.model.release_closing();
        self.resolving.set(false);
    }

    fn judged(&mut self, kept: bool) {
        self.say(format_args!(
            "{}",
            match kept {
                true => "second update kept",
                false => "first update kept",
            }
        ));
    }
}

impl ContactUpdates<'_> {
    /// A `-contact_monitor` line, on rank 0.
    fn say(&self, line: std::fmt::Arguments) {
        if self.monitor && self.ev.cx.rank == 0 {
            println!("    {line}");
        }
    }
}

/// A progress line's note on the Newton iterates at which a step grew the matrix pattern, and
/// on the tangent entries it added outside the pattern, for which PETSc reallocated rows
/// (empty when neither).
fn pattern_note(counted: &Counted) -> String {
    let grown = match counted.pattern_grown {
        0 => String::new(),
        1 => ", matrix pattern grown at 1 Newton iterate".to_string(),
        n => format!(", matrix pattern grown at {n} Newton iterates"),
    };
    match counted.outside_pattern {
        0 => grown,
        n => format!("{grown}, {n} tangent entries outside the matrix pattern"),
    }
}
