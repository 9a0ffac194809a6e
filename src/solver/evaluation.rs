//! Evaluating the model at a Newton iterate: the displacements a rank needs, gathered from the
//! distributed solution and the load curves, and the residual and tangent assembled there with
//! one domain verdict for all ranks.

use std::time::Instant;

use mpi::collective::{CommunicatorCollectives, SystemOperation};

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::model::{Closing, DomainIssue, Model, State};
use crate::petsc::{CallbackError, Matrix, Scatter, Vector};

use super::assembly;
use super::collective::{domain_check, sum_over_ranks};
use super::Context;

/// The displacements of the state being evaluated, and the time spent assembling.
pub(super) struct Evaluator {
    scatter: Scatter,
    /// Displacement of every dof this rank touches (`3 * node + c`); others stay zero.
    pub u: Vec<f64>,
    /// The load factor.
    pub t: f64,
    /// Seconds of residual and tangent assembly since the last reset.
    pub assembly_seconds: f64,
    /// Tangent entries this rank's rows gained outside the matrix pattern since the last reset
    /// ([`Matrix::stored_entries`]; PETSc reallocates the rows for them).
    pub outside_pattern: u64,
    /// Newton iterates at which the matrix pattern grew since the last reset, and the seconds
    /// of its checks and growth there ([`super::pattern_update::hold_iterate`]; the count is
    /// the same on every rank).
    pub pattern_grown: u64,
    pub pattern_seconds: f64,
    /// Whether the last tangent was assembled whole: false where an element it met was
    /// inverted and left out (the same on every rank).
    pub tangent_whole: bool,
}

impl Evaluator {
    pub fn new(scatter: Scatter, nodes: usize) -> Evaluator {
        Evaluator {
            scatter,
            u: vec![0.0; 3 * nodes],
            t: 1.0,
            assembly_seconds: 0.0,
            outside_pattern: 0,
            pattern_grown: 0,
            pattern_seconds: 0.0,
            tangent_whole: true,
        }
    }

    /// Fills `u` from the Newton iterate `x` (free dofs) and the load curves at `t`
    /// (constrained dofs).
    pub fn load(&mut self, scene: &Scene, dofs: &DofMap, x: &Vector) -> Result<()> {
        let vals = self.scatter.gather(x)?;
        for (&d, v) in dofs.gathered_dofs.iter().zip(vals) {
            self.u[d] = v;
        }
        for c in &scene.constraints {
            let x = scene.mesh.coords[c.dof / 3];
            self.u[c.dof] = c.value_at(self.t, &scene.curves, &scene.rotations, x);
        }
        Ok(())
    }

    /// The Newton update `-y` (`y`: PETSc's search direction over the free dofs) at every dof
    /// this rank touches, indexed as `u` (constrained dofs 0).
    pub fn update_of(&mut self, dofs: &DofMap, y: &Vector) -> Result<Vec<f64>> {
        let mut du = vec![0.0; self.u.len()];
        for (&d, v) in dofs.gathered_dofs.iter().zip(self.scatter.gather(y)?) {
            du[d] = -v;
        }
        Ok(du)
    }

    /// The state of the last [`Evaluator::load`].
    pub fn state<'a>(&'a self, scene: &'a Scene) -> State<'a> {
        State {
            scene,
            u: &self.u,
            t: self.t,
        }
    }
}

/// Whether a state can be evaluated: on every rank the same domain error where it cannot.
pub(super) type Verdict = Result<(), CallbackError>;

/// The model evaluated in a run's context.
#[derive(Clone, Copy)]
pub(super) struct Evaluation<'a> {
    pub cx: &'a Context<'a>,
    pub model: &'a Model,
}

impl Evaluation<'_> {
    /// `F(x; t)` into `f` at the evaluator's load factor, timed; the domain issue of any rank
    /// as one error on all (*collective*).
    pub fn residual(&self, x: &Vector, f: &mut Vector) -> Result<Verdict> {
        let issue = self.timed(x, |at| assembly::residual(self.model, at, &self.cx.dofs, f))?;
        Ok(domain_check(&self.cx.world, issue))
    }

    /// `dF/du (x; t)` into `jac`, as [`Evaluation::residual`]; counts the entries it added
    /// outside the matrix pattern.
    pub fn jacobian(&self, x: &Vector, jac: &mut Matrix) -> Result<Verdict> {
        let before = jac.stored_entries()?;
        let issue = self.timed(x, |at| {
            assembly::jacobian(self.model, at, &self.cx.dofs, jac)
        })?;
        self.cx.evaluator.borrow_mut().outside_pattern += jac.stored_entries()? - before;
        let verdict = domain_check(&self.cx.world, issue);
        self.cx.evaluator.borrow_mut().tangent_whole = verdict.is_ok();
        Ok(verdict)
    }

    /// Loads the Newton iterate `x` into the evaluator; the update `-y` from it at every dof
    /// this rank touches ([`Evaluator::update_of`]).
    pub fn load_update(&self, x: &Vector, y: &Vector) -> Result<Vec<f64>> {
        let mut ev = self.cx.evaluator.borrow_mut();
        ev.load(self.cx.scene, &self.cx.dofs, x)?;
        ev.update_of(&self.cx.dofs, y)
    }

    /// The fraction of the update `du` (as [`Evaluation::load_update`] returns it) from the
    /// loaded iterate that stays within the contact search's reach, on this rank
    /// ([`Model::step_fraction`]).
    pub fn step_fraction(&self, du: &[f64]) -> f64 {
        let ev = self.cx.evaluator.borrow();
        self.model.step_fraction(&ev.state(self.cx.scene), du)
    }

    /// Holds the contact nodes that the update `du` (as [`Evaluation::load_update`] returns
    /// it) from the loaded iterate carries through the other surface
    /// ([`Model::hold_closing`]): how many over every rank, and the deepest; none held when
    /// that is none (*collective*).
    pub fn hold_closing(&self, du: &[f64]) -> Closing {
        let ev = self.cx.evaluator.borrow();
        let to: Vec<f64> = ev.u.iter().zip(du).map(|(u, d)| u + d).collect();
        let to = State {
            scene: self.cx.scene,
            u: &to,
            t: ev.t,
        };
        let here = self.model.hold_closing(&ev.state(self.cx.scene), &to);
        let world = &self.cx.world;
        let held = sum_over_ranks(world, here.held as u64) as usize;
        if held == 0 {
            self.model.release_closing();
        }
        let mut deepest = here.deepest;
        world.all_reduce_into(&here.deepest, &mut deepest, SystemOperation::max());
        Closing { held, deepest }
    }

    /// `F(x; t)` at load factor `t`, or `None` where a rank cannot evaluate it (*collective*).
    pub fn residual_at(&self, x: &Vector, t: f64) -> Result<Option<Vector>> {
        let mut f = x.duplicate()?;
        self.cx.evaluator.borrow_mut().t = t;
        let ok = self.residual(x, &mut f)?.is_ok();
        Ok(ok.then_some(f))
    }

    /// Loads `x` into the evaluator and runs `assemble` at its state, adding the time to the
    /// evaluator's assembly seconds.
    fn timed(
        &self,
        x: &Vector,
        assemble: impl FnOnce(&State) -> Result<Option<DomainIssue>>,
    ) -> Result<Option<DomainIssue>> {
        let mut ev = self.cx.evaluator.borrow_mut();
        let started = Instant::now();
        ev.load(self.cx.scene, &self.cx.dofs, x)?;
        let issue = assemble(&ev.state(self.cx.scene))?;
        ev.assembly_seconds += started.elapsed().as_secs_f64();
        Ok(issue)
    }
}
