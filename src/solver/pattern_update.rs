//! The matrix pattern through a run: what it holds at each step, and when the matrix is made
//! anew.
//!
//! The pattern is the couplings of the contributions that do not move (the bulk elements, tied
//! interfaces), made once at set-up ([`super::Linear::fixed_pattern`]), and those of the
//! contributions whose couplings move with the displacements (contact: the pairs its search
//! finds with a margin). Two updates keep the moving part current:
//!
//! - at a step's start the pattern **grows** to hold the couplings of the converged state, so
//!   that the predictor's residual and tangent fit it; it only grows there, so that the matrix
//!   (and with it the last Newton factorization the predictor may reuse) is kept whenever it
//!   already holds them;
//! - at the predicted end of a step (once the load-step predictor, `steps.predictor`, moved the
//!   iterate; a failed prediction keeps the pattern) it is **renewed**: the fixed couplings,
//!   those of the step's start and those of the predicted iterate, and nothing else. A step
//!   that slides farther than the search margin then still finds its pairs inside the pattern,
//!   and the couplings a contact zone left behind (or a prediction that overshot) are dropped
//!   instead of being carried, as stored zeros, to the run's end.
//!
//! Without the predictor only the step-start update runs, and the pattern only grows.
//! Whenever the pattern changes on some rank every rank makes a new matrix with it
//! (collectively). Both updates are timed in the `pattern` phase (a PETSc log stage too), which
//! a scene without moving couplings never enters.
//!
//! Inside a step the Newton iterates stray from the two states. Before each Newton tangent
//! [`hold_iterate`] asks the moving contributions whether the couplings they handed out hold
//! those of the iterate (contact: the pairs that the residual's search found there, compared
//! with those handed out; a search of its own where the last residual was at other positions);
//! where they do not on some rank, the pattern grows by the iterate's couplings and the matrix
//! is preallocated anew in place (the nonlinear solver holds it), so that its entries never
//! fall outside the pattern, for which PETSc would reallocate the rows entry by entry. That
//! time counts in the `pattern` phase too.

use std::time::Instant;

use crate::error::Result;
use crate::model::Contribution;

use super::assembly::Pattern;
use super::collective::{any_rank, sum_over_ranks};
use super::evaluation::Evaluation;
use super::predictor::NewtonTangent;
use super::setup::new_matrix;
use super::Run;
use crate::petsc::{Matrix, Vector};

/// The phase (`summary.json`'s `timings`, and a PETSc log stage) of the pattern updates and
/// the new matrices they make.
pub(super) const PATTERN_PHASE: &str = "pattern";

impl Run<'_> {
    /// Grows the pattern to hold the moving couplings of the current iterate at load `t` (a
    /// step's start; module docs); a new matrix when it grew on some rank (*collective*).
    pub(super) fn grow_pattern(&mut self, t: f64) -> Result<()> {
        if !self.model.pattern_moves() {
            return Ok(());
        }
        let started = Instant::now();
        let _stage = self.phases.push(PATTERN_PHASE)?;
        let grew = {
            let moving = moving_parts(&self.model);
            let mut ev = self.cx.evaluator.borrow_mut();
            ev.t = t;
            ev.load(self.cx.scene, &self.cx.dofs, &self.linear.x)?;
            let at = ev.state(self.cx.scene);
            self.linear
                .pattern
                .add(&self.cx.dofs, &at, moving.into_iter())
        };
        if any_rank(&self.cx.world, grew) {
            self.remake_matrix()?;
        }
        self.phases
            .add(PATTERN_PHASE, started.elapsed().as_secs_f64());
        Ok(())
    }

    /// Makes the pattern anew at the predicted end of the step from `t` to `t_new`: the fixed
    /// couplings, the moving ones of the step's start (the last converged state) and of the
    /// predicted iterate (module docs); a new matrix when it changed on some rank. Returns its
    /// seconds (*collective*).
    pub(super) fn renew_pattern(&mut self, t: f64, t_new: f64) -> Result<f64> {
        if !self.model.pattern_moves() {
            return Ok(0.0);
        }
        let started = Instant::now();
        let _stage = self.phases.push(PATTERN_PHASE)?;
        let mut renewed = self.linear.fixed_pattern.clone();
        {
            let moving = moving_parts(&self.model);
            moving.iter().for_each(|part| part.forget_couplings());
            let mut ev = self.cx.evaluator.borrow_mut();
            for (load, x) in [(t, &self.linear.x_prev), (t_new, &self.linear.x)] {
                ev.t = load;
                ev.load(self.cx.scene, &self.cx.dofs, x)?;
                let at = ev.state(self.cx.scene);
                renewed.add(&self.cx.dofs, &at, moving.iter().copied());
            }
        }
        let changed = renewed != self.linear.pattern;
        if any_rank(&self.cx.world, changed) {
            self.linear.pattern = renewed;
            self.remake_matrix()?;
        }
        let seconds = started.elapsed().as_secs_f64();
        self.phases.add(PATTERN_PHASE, seconds);
        Ok(seconds)
    }

    /// The entries the matrix stores, over the ranks (*collective*).
    pub(super) fn matrix_entries(&self) -> Result<u64> {
        let mine = self.linear.jac.stored_entries()?;
        Ok(sum_over_ranks(&self.cx.world, mine))
    }

    /// A new matrix with the current pattern, whose tangent is not the last Newton one
    /// (*collective*).
    pub(super) fn remake_matrix(&mut self) -> Result<()> {
        let linear = &mut self.linear;
        let moves = self.model.pattern_moves();
        linear.jac = new_matrix(&linear.pattern, &self.cx.dofs, &linear.rigid_modes, moves)?;
        linear.tangent.newton = NewtonTangent::Other;
        Ok(())
    }
}

/// Before a Newton tangent at `x`: where the couplings the moving contributions handed out do
/// not hold those of `x` on some rank, grows `pattern` by them and, where it grew on some
/// rank, preallocates `jac` anew with it (module docs); counted and timed in the evaluator
/// (*collective*).
pub(super) fn hold_iterate(
    ev: &Evaluation,
    pattern: &mut Pattern,
    x: &Vector,
    jac: &mut Matrix,
) -> Result<()> {
    let moving = moving_parts(ev.model);
    if moving.is_empty() {
        return Ok(());
    }
    let started = Instant::now();
    let grew = grow_to_hold(ev, pattern, x, &moving)?;
    if grew {
        jac.preallocate_again(&pattern.sparsity(&ev.cx.dofs))?;
    }
    let mut evaluator = ev.cx.evaluator.borrow_mut();
    evaluator.pattern_grown += u64::from(grew);
    evaluator.pattern_seconds += started.elapsed().as_secs_f64();
    Ok(())
}

/// [`hold_iterate`]'s check and growth of `pattern`; whether it grew on some rank
/// (*collective*).
fn grow_to_hold(
    ev: &Evaluation,
    pattern: &mut Pattern,
    x: &Vector,
    moving: &[&dyn Contribution],
) -> Result<bool> {
    let (cx, world) = (ev.cx, &ev.cx.world);
    let mut evaluator = cx.evaluator.borrow_mut();
    evaluator.load(cx.scene, &cx.dofs, x)?;
    let at = evaluator.state(cx.scene);
    let held = moving.iter().all(|part| part.holds_couplings_of(&at));
    if !any_rank(world, !held) {
        return Ok(false);
    }
    let grew = pattern.add(&cx.dofs, &at, moving.iter().copied());
    Ok(any_rank(world, grew))
}

/// The contributions whose couplings move with the displacements.
fn moving_parts(model: &crate::model::Model) -> Vec<&dyn Contribution> {
    model
        .parts()
        .iter()
        .filter(|c| c.pattern_moves())
        .map(|c| c.as_ref())
        .collect()
}
