//! Newton's method through PETSc's SNES, with the residual and Jacobian as Rust closures.
//!
//! The closures are handed to [`Snes::solve`] for the duration of one solve, through a context
//! on the Rust stack. Each C callback (a trampoline) wraps the closure in `catch_unwind`: a panic
//! never unwinds into PETSc; it is stored, PETSc is told the callback failed, and the panic is
//! re-raised after `SNESSolve` returns. An error a closure returns is stored and returned the
//! same way. A [`CallbackError::Domain`] (an inverted element, a NaN) is reported to PETSc with
//! `SNESSetFunctionDomainError` / `SNESSetJacobianDomainError`, so the line search can back off
//! or the solve ends with `SNES_DIVERGED_FUNCTION_DOMAIN` and the step is cut.
//!
//! Defaults set here, all overridable from the options database: Newton with full steps
//! (`newtonls` with the `basic` line search), a direct solve (`preonly` + `lu` through MUMPS,
//! which does not need symmetry and gives the same answer on any number of ranks).
//!
//! Why full steps: the globalization is the load-step cutting of `crate::solver`, as in most
//! finite-element codes. A backtracking line search on ||F||^2 (`bt`) stalls on slender
//! structures, where the first full Newton step of a bending increment raises ||F|| (axial
//! stretch from the linearized rotation) and the next ones converge quadratically
//! (docs/performance.md, "Newton on frictional contact"). `-snes_linesearch_type bt` (or `cp`,
//! `l2`) still selects another.
//!
//! Frictional contact, whose residual is only piecewise smooth (open, stick, slip), also starts
//! with full steps; `crate::solver` redoes a solve that they do not converge with another line
//! search ([`Snes::set_line_search`]) before it cuts the step.

use std::any::Any;
use std::os::raw::c_void;
use std::panic::{catch_unwind, AssertUnwindSafe};

use petsc_ffi as p;

use super::{chk, Matrix, PetscInt, Vector};
use crate::error::{Error, Result};

/// How a residual or Jacobian evaluation failed.
#[derive(Debug)]
pub enum CallbackError {
    /// The state is outside the domain of the function (inverted element, NaN): recoverable by a
    /// shorter Newton step or a smaller load step.
    Domain(String),
    /// Anything else: the solve stops and this error is returned.
    Fatal(Error),
}

impl From<Error> for CallbackError {
    fn from(e: Error) -> Self {
        CallbackError::Fatal(e)
    }
}

/// What one nonlinear solve did.
#[derive(Clone, Debug)]
pub struct SnesOutcome {
    /// True for a positive converged reason.
    pub converged: bool,
    /// PETSc's converged reason, as its name.
    pub reason: &'static str,
    /// Newton iterations.
    pub iterations: usize,
    /// Linear iterations over the solve.
    pub linear_iterations: usize,
    /// Residual 2-norm before each iteration and at the end.
    pub residual_history: Vec<f64>,
    /// The last domain error reported by a callback, if any.
    pub domain_error: Option<String>,
    /// The line search took less than the full Newton step at some iteration (`lambda` below
    /// the line search's damping, 1 by default; never with full steps; the contact reach's
    /// shortening of an update is not the line search's and does not count). Read by the
    /// default convergence test only: false when `-snes_convergence_test` replaces it.
    pub shortened: bool,
    /// Newton updates solved a second time ([`UpdateCheck`]; `linear_iterations` counts their
    /// linear iterations), and those the second update replaced.
    pub second_solves: usize,
    pub second_solves_kept: usize,
}

/// Newton settings that a scene sets; `-snes_*` options override them.
#[derive(Clone, Copy, Debug)]
pub struct Tolerances {
    pub atol: f64,
    pub rtol: f64,
    pub stol: f64,
    pub max_it: usize,
}

/// SNES's tolerances as `SNESGetTolerances` gives them.
#[derive(Clone, Copy, Default)]
struct SnesTolerances {
    atol: f64,
    rtol: f64,
    stol: f64,
    max_it: PetscInt,
    max_f: PetscInt,
}

/// The linear solver of `snes`.
fn ksp_of(snes: p::SNES) -> Result<p::KSP> {
    let mut ksp: p::KSP = std::ptr::null_mut();
    chk!(SNESGetKSP(snes, &mut ksp))?;
    Ok(ksp)
}

/// The tolerances of `ksp`: relative, absolute, divergence, iterations (`KSPGetTolerances`).
fn ksp_tolerances(ksp: p::KSP) -> Result<(f64, f64, f64, PetscInt)> {
    let (mut rtol, mut atol, mut dtol, mut max_it) = (0.0, 0.0, 0.0, 0);
    chk!(KSPGetTolerances(
        ksp,
        &mut rtol,
        &mut atol,
        &mut dtol,
        &mut max_it
    ))?;
    Ok((rtol, atol, dtol, max_it))
}

/// A PETSc type name as a `String` (empty for null).
///
/// # Safety
/// `name` is null or a NUL-terminated string that lives through the call (PETSc's type names
/// are static).
unsafe fn type_name(name: *const std::os::raw::c_char) -> String {
    if name.is_null() {
        return String::new();
    }
    // SAFETY: the caller's promise.
    unsafe { std::ffi::CStr::from_ptr(name) }
        .to_string_lossy()
        .into_owned()
}

/// A PETSc error met while reading the options: an [`Error::Options`] naming their source and,
/// when PETSc's message quotes a bad value without its option ("Input string abc has no integer
/// value"), the options that hold that value.
fn options_error(options_source: &str, e: Error) -> Error {
    let Error::Petsc { msg, .. } = e else {
        return e;
    };
    let quoted = msg
        .strip_prefix("Input string ")
        .or_else(|| msg.strip_prefix("Unknown logical value: "))
        .and_then(|rest| rest.split_whitespace().next());
    let holders = quoted.map_or_else(Vec::new, super::options::named_by_value);
    let msg = match (quoted, holders.is_empty()) {
        (Some(value), false) => {
            let named: Vec<String> = holders.iter().map(|n| format!("{n} {value}")).collect();
            format!("{}: {msg}", named.join(", "))
        }
        _ => msg,
    };
    Error::Options {
        source_name: options_source.to_string(),
        msg,
    }
}

type ResidualFn<'a> = dyn FnMut(&Vector, &mut Vector) -> Result<(), CallbackError> + 'a;
type JacobianFn<'a> = dyn FnMut(&Vector, &mut Matrix) -> Result<(), CallbackError> + 'a;
/// The line search's pre-check of every Newton update `-y` from `x`.
///
/// [`UpdateCheck::limit`] shortens the update. Where [`UpdateCheck::ask`] then says so, the
/// update is solved a second time: the tangent and residual at `x` are assembled again (with
/// the law as `ask` left it) and the update solved with them, at the linear tolerance of the
/// first solve; after [`UpdateCheck::release`], the second update (shortened by `limit` too)
/// replaces the first where the solve's residual at its full step is the smaller. Second
/// solves are made only with full steps and `bt`, the line searches whose first trial is the
/// full step.
pub trait UpdateCheck {
    /// The fraction (at most 1, above 0 for a finite update) of the update `-y` from `x` to
    /// take (*collective*: the same on every rank).
    fn limit(&mut self, x: &Vector, y: &Vector) -> Result<f64, CallbackError>;
    /// Whether to solve the update `-y` from `x` again: true once the caller changed its
    /// residual's law at `x` for the second solve (*collective*). Called right after the
    /// `limit` that shortened `y`, with nothing evaluated between. Never, unless implemented.
    fn ask(&mut self, _x: &Vector, _y: &Vector) -> Result<bool, CallbackError> {
        Ok(false)
    }
    /// The second solve is over: the law as it was before `ask`.
    fn release(&mut self) {}
    /// Whether the second update replaced the first.
    fn judged(&mut self, _kept: bool) {}
}

enum Failure {
    Panic(Box<dyn Any + Send>),
    Error(Error),
}

struct Context<'a> {
    residual: &'a mut ResidualFn<'a>,
    jacobian: &'a mut JacobianFn<'a>,
    update_check: Option<&'a mut dyn UpdateCheck>,
    /// The second solves of the solve under way: made, kept, and their linear iterations.
    second_solves: usize,
    second_solves_kept: usize,
    second_solve_its: usize,
    /// The solver's [`Multigrid`] during the solve (written back after it).
    multigrid: Multigrid,
    failure: Option<Failure>,
    domain_error: Option<String>,
}

/// What the multigrid of the iterative path does at the set-up after the next Jacobian
/// ([`Snes::rebuild_multigrid`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Multigrid {
    /// Whatever the options say (the direct path, or the user's own reuse option).
    AsTheOptionsSay,
    /// Set it up anew: interpolation, coarse operators, smoothers.
    Rebuild,
    /// Keep it whole as last set up: no set-up at all.
    Keep,
}

/// A PETSc nonlinear solver; destroyed on drop.
pub struct Snes {
    raw: p::SNES,
    history: Vec<f64>,
    /// The convergence test's state ([`Snes::stop_on_cycling`]); boxed, as PETSc holds its
    /// address.
    cycling: Box<Cycling>,
    /// What the multigrid does at the set-up after the next Jacobian
    /// ([`Snes::rebuild_multigrid`]).
    multigrid: Multigrid,
    /// The linear solver's relative tolerance as the options set it (`-ksp_rtol`), for the
    /// solves outside Newton while inexact Newton changes it at every Newton step.
    linear_rtol: f64,
}

/// The convergence test's own state: the last residual norms of a solve, for
/// [`Snes::stop_on_cycling`], and the scale of its round-off floor
/// ([`Snes::set_round_off_length`]).
#[derive(Default)]
struct Cycling {
    /// The least progress over two iterations (`None`: never stop).
    progress: Option<f64>,
    /// The norms of the last two iterations, the latest first.
    last: [f64; 2],
    /// The size of the positions whose round-off the residual carries (0: no floor).
    length: f64,
    /// The floor of the last test, and whether it ended the last solve.
    floor: f64,
    at_floor: bool,
    /// The line search shortened a step of the solve under way ([`SnesOutcome::shortened`]).
    shortened: bool,
}

/// The round-off floor of a residual norm, in units of `eps |K_ii|_max (L + |u|_max)`: a
/// residual assembled from forces `K x` of positions of size `L + |u|` cannot be resolved below
/// `eps |K| |x|` per row, and a few rows at the largest diagonal (the stiffest penalty) carry
/// it (docs/theory.md, section 10, "Round-off floor").
pub const ROUND_OFF_FACTOR: f64 = 4.0;

impl Snes {
    /// A Newton solver with the project's defaults and the line search `line_search` (`basic`:
    /// full steps; `bt`: backtracking), then `SNESSetFromOptions`, and, when its Newton steps
    /// factorize, the factorization set up once on a small matrix
    /// (`ksp::probe_factorization`), so that every option is checked before the first
    /// step. `options_source` names where the options came from, for the error message when
    /// one is invalid. Collective.
    pub fn new(
        tol: Tolerances,
        options_source: &str,
        line_search: &str,
        path: super::ksp::LinearPath,
    ) -> Result<Snes> {
        super::ensure_initialized()?;
        let mut raw: p::SNES = std::ptr::null_mut();
        chk!(SNESCreate(super::comm(), &mut raw))?;
        let mut user_reuse = false;
        for name in super::ksp::MULTIGRID_REUSE {
            user_reuse |= super::options::has(name)?;
        }
        let multigrid = match path {
            super::ksp::LinearPath::Iterative { .. } if !user_reuse => Multigrid::Keep,
            _ => Multigrid::AsTheOptionsSay,
        };
        let mut snes = Snes {
            raw,
            history: Vec::new(),
            cycling: Box::default(),
            multigrid,
            linear_rtol: 0.0,
        };
        let cycling = &mut *snes.cycling as *mut Cycling as *mut c_void;
        chk!(SNESSetConvergenceTest(
            snes.raw,
            Some(convergence_trampoline),
            cycling,
            None
        ))?;
        chk!(SNESSetType(snes.raw, c"newtonls".as_ptr()))?;
        let mut ls: p::SNESLineSearch = std::ptr::null_mut();
        chk!(SNESGetLineSearch(snes.raw, &mut ls))?;
        let line_search = std::ffi::CString::new(line_search)
            .map_err(|_| Error::Solve(format!("bad line search name {line_search:?}")))?;
        chk!(SNESLineSearchSetType(ls, line_search.as_ptr()))?;
        chk!(SNESSetCheckJacobianDomainError(
            snes.raw,
            p::PetscBool::PETSC_TRUE
        ))?;
        super::ksp::set_linear_solver_defaults(path)?;
        chk!(SNESSetTolerances(
            snes.raw,
            tol.atol,
            tol.rtol,
            tol.stol,
            super::to_petsc_int(tol.max_it)?,
            -1
        ))?;
        chk!(SNESSetFromOptions(snes.raw)).map_err(|e| options_error(options_source, e))?;
        let mut max_it: PetscInt = 0;
        let mut max_f: PetscInt = 0;
        let (mut atol, mut rtol, mut stol) = (0.0, 0.0, 0.0);
        chk!(SNESGetTolerances(
            snes.raw,
            &mut atol,
            &mut rtol,
            &mut stol,
            &mut max_it,
            &mut max_f
        ))?;
        // PETSc takes any number here; a NaN or negative tolerance would never stop Newton.
        for (name, value) in [("atol", atol), ("rtol", rtol), ("stol", stol)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::Options {
                    source_name: options_source.to_string(),
                    msg: format!("-snes_{name} {value}: must be finite and >= 0"),
                });
            }
        }
        if max_it < 0 {
            // PETSc would stop at once without a reason ("Internal error").
            return Err(Error::Options {
                source_name: options_source.to_string(),
                msg: format!("-snes_max_it {max_it}: must be >= 0"),
            });
        }
        snes.linear_rtol = ksp_tolerances(ksp_of(snes.raw)?)?.0;
        if snes.factorizes()? {
            super::ksp::probe_factorization().map_err(|e| options_error(options_source, e))?;
        }
        snes.history = vec![0.0; max_it.max(1) as usize + 2];
        Ok(snes)
    }

    /// True when this solver's Newton steps factorize: a Newton type with a Jacobian
    /// (`newtonls`, `newtontr`; not `-snes_mf`, whose preconditioner is none) whose linear
    /// solver's preconditioner is one [`super::ksp::probe_factorization`] checks.
    fn factorizes(&self) -> Result<bool> {
        let mut snes_type: p::SNESType = std::ptr::null();
        chk!(SNESGetType(self.raw, &mut snes_type))?;
        // SAFETY: PETSc returns its static type name, or null.
        if !matches!(
            unsafe { type_name(snes_type) }.as_str(),
            "newtonls" | "newtontr"
        ) {
            return Ok(false);
        }
        Ok(super::ksp::is_probed_factorization(
            &self.preconditioner()?.1,
        ))
    }

    /// The preconditioner of this solver's linear solver, and its type name (empty before
    /// one is set).
    fn preconditioner(&self) -> Result<(p::PC, String)> {
        preconditioner_of(self.raw)
    }

    /// Solves F(x) = 0 from the initial guess in `x` (overwritten by the solution).
    ///
    /// `residual(x, f)` writes F(x) into `f`; `jacobian(x, J)` assembles dF/dx into `J` (the
    /// matrix passed here, whose pattern must hold every entry). Closures that share state can
    /// hold it in a `RefCell`.
    pub fn solve<'a>(
        &mut self,
        x: &mut Vector,
        jac: &mut Matrix,
        residual: &'a mut ResidualFn<'a>,
        jacobian: &'a mut JacobianFn<'a>,
    ) -> Result<SnesOutcome> {
        self.solve_limited(x, jac, (residual, jacobian), None)
    }

    /// [`Snes::solve`], with every Newton update checked by `update_check` (a pre-check of
    /// the line search): shortened to the fraction [`UpdateCheck::limit`] says (`basic` and
    /// `bt` take at most the shortened update, `l2` searches along it and may go beyond), and
    /// solved a second time where [`UpdateCheck::ask`] says so.
    pub fn solve_limited<'a>(
        &mut self,
        x: &mut Vector,
        jac: &mut Matrix,
        (residual, jacobian): (&'a mut ResidualFn<'a>, &'a mut JacobianFn<'a>),
        update_check: Option<&'a mut dyn UpdateCheck>,
    ) -> Result<SnesOutcome> {
        let limited = update_check.is_some();
        let mut ctx = Context {
            residual,
            jacobian,
            update_check,
            second_solves: 0,
            second_solves_kept: 0,
            second_solve_its: 0,
            multigrid: self.multigrid,
            failure: None,
            domain_error: None,
        };
        let ctx_ptr = &mut ctx as *mut Context as *mut c_void;
        let f = x.duplicate()?;
        chk!(SNESSetFunction(
            self.raw,
            f.raw,
            Some(residual_trampoline),
            ctx_ptr
        ))?;
        chk!(SNESSetJacobian(
            self.raw,
            jac.raw,
            jac.raw,
            Some(jacobian_trampoline),
            ctx_ptr
        ))?;
        composite_operators(self.raw, jac)?;
        let n = super::to_petsc_int(self.history.len())?;
        chk!(SNESSetConvergenceHistory(
            self.raw,
            self.history.as_mut_ptr(),
            std::ptr::null_mut(),
            n,
            p::PetscBool::PETSC_TRUE
        ))?;
        let mut ls: p::SNESLineSearch = std::ptr::null_mut();
        chk!(SNESGetLineSearch(self.raw, &mut ls))?;
        if limited {
            chk!(SNESLineSearchSetPreCheck(
                ls,
                Some(pre_check_trampoline),
                ctx_ptr
            ))?;
        }
        self.cycling.shortened = false;
        let solved = chk!(SNESSolve(self.raw, std::ptr::null_mut(), x.raw));
        self.multigrid = ctx.multigrid;
        // Detach the context: it lives on this stack frame only.
        if limited {
            chk!(SNESLineSearchSetPreCheck(ls, None, std::ptr::null_mut()))?;
        }
        chk!(SNESSetFunction(
            self.raw,
            f.raw,
            Some(residual_trampoline),
            std::ptr::null_mut()
        ))?;
        chk!(SNESSetJacobian(
            self.raw,
            jac.raw,
            jac.raw,
            Some(jacobian_trampoline),
            std::ptr::null_mut()
        ))?;
        match ctx.failure.take() {
            Some(Failure::Panic(payload)) => std::panic::resume_unwind(payload),
            Some(Failure::Error(e)) => return Err(e),
            None => solved?,
        }
        let mut outcome = self.outcome(ctx.domain_error)?;
        outcome.linear_iterations += ctx.second_solve_its;
        outcome.second_solves = ctx.second_solves;
        outcome.second_solves_kept = ctx.second_solves_kept;
        Ok(outcome)
    }

    /// On the iterative path (unless the user's options say whether GAMG reuses its
    /// interpolation, `ksp::MULTIGRID_REUSE`): the preconditioner's multigrid (GAMG on the
    /// whole matrix, or on a field of the field split) is set up anew after the next Jacobian,
    /// and kept whole at the later ones (interpolation, coarse operators and smoothers: no
    /// set-up; the rest of the preconditioner, the interface's factorization, is set up at
    /// every Jacobian) until this is called again. Called once per load step, the multigrid
    /// follows the deformation at the price of one set-up per step, not per Newton iteration;
    /// PETSc's default would keep the first set-up's interpolation for the whole run.
    pub fn rebuild_multigrid(&mut self) {
        if self.multigrid != Multigrid::AsTheOptionsSay {
            self.multigrid = Multigrid::Rebuild;
        }
    }

    /// From the next solve on, stop a solve (`DIVERGED_DTOL`) that cycles: its residual norm
    /// rises at an iteration `k >= 2` to above `progress` times the norm of iteration `k - 2`
    /// (`None`: never; PETSc's test alone). Full Newton steps on a piecewise smooth residual
    /// may cycle between two sets of states (open and closed, stick and slip), the norm going
    /// up and down between the same two levels; a solve that then falls back to another line
    /// search should not spend its iterations first. (Only while PETSc's default convergence
    /// test is in place: `-snes_convergence_test` replaces it.)
    pub fn stop_on_cycling(&mut self, progress: Option<f64>) {
        self.cycling.progress = progress;
    }

    /// The size `L` of the positions (the mesh's largest coordinate): from the next solve on, a
    /// residual norm below the round-off floor `ROUND_OFF_FACTOR eps |K_ii|_max (L + |u|_max)`
    /// ([`ROUND_OFF_FACTOR`]; the tangent's largest diagonal entry, the largest displacement)
    /// counts as converged (`CONVERGED_FNORM_ABS`), whatever `atol`: Newton cannot go below
    /// it, and without it a stiff penalty would stall above `atol` until `max_it`.
    pub fn set_round_off_length(&mut self, length: f64) {
        self.cycling.length = length;
    }

    /// The round-off floor of the last convergence test, and whether the last solve converged
    /// by reaching it rather than `atol` or `rtol`.
    pub fn round_off_floor(&self) -> (f64, bool) {
        (self.cycling.floor, self.cycling.at_floor)
    }

    /// For a problem whose tangent never changes (linear materials, dead loads, tying): the
    /// Jacobian is computed and factorized at the first chance, then reused by every later
    /// solve (`SNESSetLagJacobian(-2)`, persisting across solves).
    pub fn freeze_jacobian(&mut self) -> Result<()> {
        chk!(SNESSetLagJacobian(self.raw, -2))?;
        chk!(SNESSetLagJacobianPersists(
            self.raw,
            p::PetscBool::PETSC_TRUE
        ))
    }

    /// The line search's type name (`basic`, `bt`, `l2`, ...), as set by [`Snes::new`] or the
    /// options database.
    pub fn line_search(&self) -> Result<String> {
        let mut ls: p::SNESLineSearch = std::ptr::null_mut();
        chk!(SNESGetLineSearch(self.raw, &mut ls))?;
        let mut name: p::SNESLineSearchType = std::ptr::null();
        chk!(SNESLineSearchGetType(ls, &mut name))?;
        // SAFETY: PETSc returns its static type name, or null.
        Ok(unsafe { type_name(name) })
    }

    /// Switches the line search of the next solves to `name` (`basic`, `bt`, `l2`, ...).
    pub fn set_line_search(&mut self, name: &str) -> Result<()> {
        let mut ls: p::SNESLineSearch = std::ptr::null_mut();
        chk!(SNESGetLineSearch(self.raw, &mut ls))?;
        let c = std::ffi::CString::new(name)
            .map_err(|_| Error::Solve(format!("bad line search name {name:?}")))?;
        chk!(SNESLineSearchSetType(ls, c.as_ptr()))
    }

    /// Names the two fields of a field-split preconditioner (`-pc_type fieldsplit`, or the
    /// first field split of a composite; returns false and does nothing for another):
    /// `interface`, the owned global dofs `interface` (sorted), and `bulk`, the other owned
    /// dofs `[start, start + count)`, with `modes` (a near null space on the owned rows)
    /// restricted to them as the bulk's near null space, for multigrid. A composite's `shell`
    /// part after the split becomes the split's interface coarse correction
    /// (`super::coarse`). Before the first solve. Collective.
    pub fn split_interface(
        &mut self,
        interface: &[PetscInt],
        (start, count): (usize, usize),
        modes: &[Vec<f64>],
    ) -> Result<bool> {
        let (top, top_type) = self.preconditioner()?;
        let Some(pc) = fieldsplit_within(top, &top_type)? else {
            return Ok(false);
        };
        let mut in_interface = vec![false; count];
        for &g in interface {
            in_interface[g as usize - start] = true;
        }
        let bulk_rows: Vec<usize> = (0..count).filter(|&k| !in_interface[k]).collect();
        let bulk: Vec<PetscInt> = bulk_rows.iter().map(|&k| (start + k) as PetscInt).collect();
        let bulk_modes: Vec<Vec<f64>> = modes
            .iter()
            .map(|m| bulk_rows.iter().map(|&k| m[k]).collect())
            .collect();
        let interface_set = super::IndexSet::new(interface)?;
        let bulk_set = super::IndexSet::new(&bulk)?;
        bulk_set.attach_near_null_space(&super::matrix::NullSpace::of(&bulk_modes)?)?;
        chk!(PCFieldSplitSetIS(
            pc,
            c"interface".as_ptr(),
            interface_set.raw
        ))?;
        chk!(PCFieldSplitSetIS(pc, c"bulk".as_ptr(), bulk_set.raw))?;
        let parts = composite_parts(top, &top_type)?;
        let after_split = parts.iter().skip_while(|&&part| part != pc).skip(1);
        for &part in after_split {
            if pc_type_name(part)? == "shell" {
                super::coarse::attach(part, pc)?;
            }
        }
        Ok(true)
    }

    /// The largest number of Newton iterations of the next solves (the other tolerances are
    /// kept); returns the previous value.
    pub fn set_max_iterations(&mut self, max_it: usize) -> Result<usize> {
        let max_it = super::to_petsc_int(max_it)?;
        let old = self.change_tolerances(|t| t.max_it = max_it)?;
        Ok(old.max_it.max(0) as usize)
    }

    /// The relative tolerance of the next solves (the other tolerances are kept); returns the
    /// previous value.
    pub fn set_relative_tolerance(&mut self, rtol: f64) -> Result<f64> {
        Ok(self.change_tolerances(|t| t.rtol = rtol)?.rtol)
    }

    /// Applies `change` to SNES's tolerances; returns them as they were.
    fn change_tolerances(
        &mut self,
        change: impl FnOnce(&mut SnesTolerances),
    ) -> Result<SnesTolerances> {
        let mut t = SnesTolerances::default();
        chk!(SNESGetTolerances(
            self.raw,
            &mut t.atol,
            &mut t.rtol,
            &mut t.stol,
            &mut t.max_it,
            &mut t.max_f
        ))?;
        let old = t;
        change(&mut t);
        chk!(SNESSetTolerances(
            self.raw, t.atol, t.rtol, t.stol, t.max_it, t.max_f
        ))?;
        Ok(old)
    }

    /// Makes the next solves take at least one Newton iteration even when the first residual
    /// is already below the tolerances (after an Uzawa update, say).
    pub fn force_iteration(&mut self, on: bool) -> Result<()> {
        let flag = if on {
            p::PetscBool::PETSC_TRUE
        } else {
            p::PetscBool::PETSC_FALSE
        };
        chk!(SNESSetForceIteration(self.raw, flag))
    }

    /// For a constant tangent already assembled in the Jacobian matrix (and factorized by
    /// [`Snes::linear_solve`]): never recompute it (`SNESSetLagJacobian(-1)`, persisting).
    pub fn reuse_jacobian(&mut self) -> Result<()> {
        chk!(SNESSetLagJacobian(self.raw, -1))?;
        chk!(SNESSetLagJacobianPersists(
            self.raw,
            p::PetscBool::PETSC_TRUE
        ))
    }

    /// Solves `a x = b` with the solver's own linear solver (sharing its factorization when
    /// `a` is the Jacobian matrix and unchanged).
    pub fn linear_solve(&mut self, a: &Matrix, b: &Vector, x: &mut Vector) -> Result<bool> {
        let ksp = ksp_of(self.raw)?;
        chk!(KSPSetOperators(ksp, a.raw, a.raw))?;
        composite_operators(self.raw, a)?;
        // Eisenstat-Walker's tolerance (`-snes_ksp_ew`) is computed from the norms of a
        // running Newton solve, which a solve outside it lacks: this one takes the options'
        // own tolerance instead of the last Newton step's.
        solve_without_ew(self.raw, b, x, Some(self.linear_rtol))
    }

    /// Null pivots MUMPS met in the last factorization (`INFOG(28)`, with null-pivot detection
    /// on, as by default), or `None` when the linear solver is not a MUMPS factorization or
    /// nothing was factorized yet. The predictor's solves count: they use this solver's KSP.
    pub fn null_pivots(&self) -> Result<Option<usize>> {
        let (pc, pc_type) = self.preconditioner()?;
        if !matches!(pc_type.as_str(), "lu" | "cholesky") {
            return Ok(None);
        }
        let mut solver: p::MatSolverType = std::ptr::null();
        chk!(PCFactorGetMatSolverType(pc, &mut solver))?;
        // SAFETY: PETSc returns its static type name, or null.
        if unsafe { type_name(solver) } != "mumps" {
            return Ok(None);
        }
        let mut factor: p::Mat = std::ptr::null_mut();
        if chk!(PCFactorGetMatrix(pc, &mut factor)).is_err() {
            // Nothing factorized yet (no linear solve so far): nothing to report.
            return Ok(None);
        }
        let mut n: PetscInt = 0;
        chk!(MatMumpsGetInfog(factor, 28, &mut n))?;
        Ok(Some(n.max(0) as usize))
    }

    fn outcome(&self, domain_error: Option<String>) -> Result<SnesOutcome> {
        let mut reason = p::SNESConvergedReason(0);
        chk!(SNESGetConvergedReason(self.raw, &mut reason))?;
        let mut its: PetscInt = 0;
        chk!(SNESGetIterationNumber(self.raw, &mut its))?;
        let mut lits: PetscInt = 0;
        chk!(SNESGetLinearSolveIterations(self.raw, &mut lits))?;
        let mut hist: *mut f64 = std::ptr::null_mut();
        let mut nhist: PetscInt = 0;
        chk!(SNESGetConvergenceHistory(
            self.raw,
            &mut hist,
            std::ptr::null_mut(),
            &mut nhist
        ))?;
        let n = (nhist.max(0) as usize).min(self.history.len());
        Ok(SnesOutcome {
            converged: reason.0 > 0,
            reason: reason_name(reason.0),
            iterations: its as usize,
            linear_iterations: lits as usize,
            residual_history: self.history[..n].to_vec(),
            domain_error,
            shortened: self.cycling.shortened,
            second_solves: 0,
            second_solves_kept: 0,
        })
    }
}

impl Drop for Snes {
    fn drop(&mut self) {
        if super::is_finalized() {
            return;
        }
        // SAFETY: `raw` is a valid SNES owned by this struct.
        let code = unsafe { p::SNESDestroy(&mut self.raw) };
        if code != 0 {
            crate::error::print_warning(format_args!("SNESDestroy returned error code {code}"));
        }
    }
}

/// Runs a callback body with panics caught; maps the outcome to a PETSc error code.
///
/// # Safety
/// `ctx` must be null or the `Context` set by `Snes::solve`, alive for this call.
unsafe fn run_callback(
    ctx: *mut c_void,
    on_domain: impl FnOnce(),
    body: impl FnOnce(&mut Context) -> Result<(), CallbackError>,
) -> p::PetscErrorCode {
    if ctx.is_null() {
        return p::PETSC_ERR_USER;
    }
    let ctx = &mut *(ctx as *mut Context);
    if ctx.failure.is_some() {
        return p::PETSC_ERR_USER;
    }
    match catch_unwind(AssertUnwindSafe(|| body(ctx))) {
        Ok(Ok(())) => 0,
        Ok(Err(CallbackError::Domain(msg))) => {
            ctx.domain_error = Some(msg);
            on_domain();
            0
        }
        Ok(Err(CallbackError::Fatal(e))) => {
            ctx.failure = Some(Failure::Error(e));
            p::PETSC_ERR_USER
        }
        Err(payload) => {
            ctx.failure = Some(Failure::Panic(payload));
            p::PETSC_ERR_USER
        }
    }
}

unsafe extern "C" fn residual_trampoline(
    snes: p::SNES,
    x: p::Vec,
    f: p::Vec,
    ctx: *mut c_void,
) -> p::PetscErrorCode {
    run_callback(
        ctx,
        || {
            p::SNESSetFunctionDomainError(snes);
        },
        |c| {
            let xv = Vector::from_borrowed(x)?;
            let mut fv = Vector::from_borrowed(f)?;
            (c.residual)(&xv, &mut fv)
        },
    )
}

unsafe extern "C" fn jacobian_trampoline(
    snes: p::SNES,
    x: p::Vec,
    _a: p::Mat,
    pmat: p::Mat,
    ctx: *mut c_void,
) -> p::PetscErrorCode {
    run_callback(
        ctx,
        || {
            p::SNESSetJacobianDomainError(snes);
        },
        |c| {
            let xv = Vector::from_borrowed(x)?;
            let mut jm = Matrix::from_borrowed(pmat)?;
            (c.jacobian)(&xv, &mut jm)?;
            let keep = match c.multigrid {
                Multigrid::AsTheOptionsSay => return Ok(()),
                Multigrid::Rebuild => false,
                Multigrid::Keep => true,
            };
            set_multigrid_reuse(snes, keep)?;
            c.multigrid = Multigrid::Keep;
            Ok(())
        },
    )
}

/// Tells the multigrid of `snes`'s preconditioner (GAMG on the whole matrix, or GAMG in any
/// field of a field split) whether its next set-up keeps it whole (`keep`: no set-up) or sets
/// it up anew, interpolation included. Does nothing to other preconditioners, nor to a field
/// whose type is not set yet (before the split's first set-up, which builds everything
/// anyway).
fn set_multigrid_reuse(snes: p::SNES, keep: bool) -> Result<()> {
    let (pc, pc_type) = preconditioner_of(snes)?;
    let flag = if keep {
        p::PetscBool::PETSC_TRUE
    } else {
        p::PetscBool::PETSC_FALSE
    };
    let pcs = match fieldsplit_within(pc, &pc_type)? {
        Some(split) => field_preconditioners(split)?,
        None => vec![pc],
    };
    for pc in pcs {
        if pc_type_name(pc)? == "gamg" {
            chk!(PCGAMGSetReuseInterpolation(pc, flag))?;
            chk!(PCSetReusePreconditioner(pc, flag))?;
        }
    }
    Ok(())
}

/// A composite preconditioner's parts get its operators at its first set-up only (PETSc 3.18's
/// `PCSetUp_Composite`): after a new matrix (the contact pattern grew) they would go on with
/// the old one. Gives them `jac`, the matrix of the solves to come.
fn composite_operators(snes: p::SNES, jac: &Matrix) -> Result<()> {
    let (pc, pc_type) = preconditioner_of(snes)?;
    for part in composite_parts(pc, &pc_type)? {
        chk!(PCSetOperators(part, jac.raw, jac.raw))?;
    }
    Ok(())
}

/// The parts of `pc` when it is a composite (of type `pc_type`); none otherwise.
fn composite_parts(pc: p::PC, pc_type: &str) -> Result<Vec<p::PC>> {
    if pc_type != "composite" {
        return Ok(Vec::new());
    }
    let mut n: PetscInt = 0;
    chk!(PCCompositeGetNumberPC(pc, &mut n))?;
    (0..n)
        .map(|k| {
            let mut part: p::PC = std::ptr::null_mut();
            chk!(PCCompositeGetPC(pc, k, &mut part)).map(|_| part)
        })
        .collect()
}

/// The preconditioner of `snes`'s linear solver, and its type name (empty before one is set).
fn preconditioner_of(snes: p::SNES) -> Result<(p::PC, String)> {
    let mut pc: p::PC = std::ptr::null_mut();
    chk!(KSPGetPC(ksp_of(snes)?, &mut pc))?;
    Ok((pc, pc_type_name(pc)?))
}

/// The type name of the preconditioner `pc` (empty before one is set).
pub(super) fn pc_type_name(pc: p::PC) -> Result<String> {
    let mut pc_type: p::PCType = std::ptr::null();
    chk!(PCGetType(pc, &mut pc_type))?;
    // SAFETY: PETSc returns its static type name, or null.
    Ok(unsafe { type_name(pc_type) })
}

/// The preconditioners of the fields of the field split `pc`; none for a Schur complement
/// split, whose fields PETSc lists only once it is set up (its multigrid is left to the
/// options).
fn field_preconditioners(pc: p::PC) -> Result<Vec<p::PC>> {
    let mut split_type = p::PCCompositeType(0);
    chk!(PCFieldSplitGetType(pc, &mut split_type))?;
    if split_type == p::PCCompositeType::PC_COMPOSITE_SCHUR {
        return Ok(Vec::new());
    }
    let mut n: PetscInt = 0;
    let mut subksp: *mut p::KSP = std::ptr::null_mut();
    chk!(PCFieldSplitGetSubKSP(pc, &mut n, &mut subksp))?;
    let pcs = (0..n.max(0) as usize)
        .map(|k| {
            let mut sub: p::PC = std::ptr::null_mut();
            // SAFETY: PETSc returned an array of `n` KSPs, freed below.
            chk!(KSPGetPC(unsafe { *subksp.add(k) }, &mut sub)).map(|_| sub)
        })
        .collect();
    // SAFETY: the array was allocated by PETSc for the caller.
    chk!(petsc_ffi_free(subksp as *mut c_void))?;
    pcs
}

/// The line search's pre-check: the [`UpdateCheck`].
unsafe extern "C" fn pre_check_trampoline(
    ls: p::SNESLineSearch,
    x: p::Vec,
    y: p::Vec,
    changed: *mut p::PetscBool,
    ctx: *mut c_void,
) -> p::PetscErrorCode {
    run_callback(
        ctx,
        || {},
        |c| {
            let xv = Vector::from_borrowed(x)?;
            let mut yv = Vector::from_borrowed(y)?;
            let mut any = limit_update(c, &xv, &mut yv)?;
            if starts_from_full_step(ls)? {
                any |= second_solve(ls, c, &xv, &mut yv)?;
            }
            if any {
                *changed = p::PetscBool::PETSC_TRUE;
            }
            Ok(())
        },
    )
}

/// The update `y` at `x` shortened by [`UpdateCheck::limit`]; whether it was.
fn limit_update(c: &mut Context, x: &Vector, y: &mut Vector) -> Result<bool, CallbackError> {
    let Some(check) = c.update_check.as_deref_mut() else {
        return Ok(false);
    };
    let fraction = check.limit(x, y)?;
    if fraction < 1.0 {
        y.scale(fraction)?;
    }
    Ok(fraction < 1.0)
}

/// Whether the line search `ls` starts from the full Newton step (full steps, `bt`): the
/// ones whose first trial judges a second solve ([`UpdateCheck::ask`]).
///
/// # Safety
/// `ls` is a valid line search.
unsafe fn starts_from_full_step(ls: p::SNESLineSearch) -> Result<bool> {
    let mut name: p::SNESLineSearchType = std::ptr::null();
    chk!(SNESLineSearchGetType(ls, &mut name))?;
    // SAFETY: PETSc returns its static type name, or null.
    Ok(matches!(type_name(name).as_str(), "basic" | "none" | "bt"))
}

/// The second solve of the update `y` at `x`, where [`UpdateCheck::ask`] wants one; true when the
/// second update replaced `y`.
///
/// # Safety
/// `ls` is the line search whose vectors `x` and `y` are, valid for this call.
unsafe fn second_solve(
    ls: p::SNESLineSearch,
    c: &mut Context,
    x: &Vector,
    y: &mut Vector,
) -> Result<bool, CallbackError> {
    let Some(check) = c.update_check.as_deref_mut() else {
        return Ok(false);
    };
    if !check.ask(x, y)? {
        return Ok(false);
    }
    c.second_solves += 1;
    let first = y.copy();
    let solved = match first {
        Ok(_) => solve_again(ls, c, x, y),
        Err(_) => Ok(false),
    };
    if let Some(check) = c.update_check.as_deref_mut() {
        check.release();
    }
    let first = first?;
    // A state the second solve cannot evaluate (or a stop asked for at its Jacobian, which
    // the next one finds again) leaves the first update.
    let solved = match solved {
        Err(CallbackError::Domain(_)) => false,
        other => other?,
    };
    // (The second update's residual last: the contact keeps its last evaluation, which the
    // line search's first trial then reuses when the second is kept.)
    let kept = solved && {
        limit_update(c, x, y)?;
        let before = full_step_norm(c, x, &first)?;
        full_step_norm(c, x, y)? < before
    };
    if kept {
        c.second_solves_kept += 1;
    } else {
        first.copy_to(y)?;
    }
    if let Some(check) = c.update_check.as_deref_mut() {
        check.judged(kept);
    }
    Ok(kept)
}

/// The update `y` at `x` solved again, with the tangent and residual assembled anew at `x`,
/// at the linear tolerance of the Newton iteration's first solve; false where the linear
/// solve failed (`y` is then undefined).
///
/// # Safety
/// `ls` is the line search whose vectors `x` and `y` are, valid for this call.
unsafe fn solve_again(
    ls: p::SNESLineSearch,
    c: &mut Context,
    x: &Vector,
    y: &mut Vector,
) -> Result<bool, CallbackError> {
    let mut snes: p::SNES = std::ptr::null_mut();
    chk!(SNESLineSearchGetSNES(ls, &mut snes))?;
    let (mut amat, mut pmat): (p::Mat, p::Mat) = (std::ptr::null_mut(), std::ptr::null_mut());
    chk!(SNESGetJacobian(
        snes,
        &mut amat,
        &mut pmat,
        std::ptr::null_mut(),
        std::ptr::null_mut()
    ))?;
    let mut jm = Matrix::from_borrowed(pmat)?;
    (c.jacobian)(x, &mut jm)?;
    // The multigrid set up for this Newton iteration serves the second solve too.
    if c.multigrid != Multigrid::AsTheOptionsSay {
        set_multigrid_reuse(snes, true)?;
    }
    let mut f = x.duplicate()?;
    (c.residual)(x, &mut f)?;
    // Eisenstat-Walker's tolerance is the one the first solve took (still the solver's):
    // computed again here it would see no progress and take its loosest.
    let solved = solve_without_ew(snes, &f, y, None)?;
    let mut its: PetscInt = 0;
    chk!(KSPGetIterationNumber(ksp_of(snes)?, &mut its))?;
    c.second_solve_its += its.max(0) as usize;
    Ok(solved)
}

/// `b` solved into `x` with the linear solver of `snes` and its operators as they are,
/// Eisenstat-Walker's tolerance (`-snes_ksp_ew`) not computed for it: at the relative
/// tolerance `rtol` where that is given and Eisenstat-Walker is on, else at the solver's
/// current one. Whether the solve converged.
fn solve_without_ew(snes: p::SNES, b: &Vector, x: &mut Vector, rtol: Option<f64>) -> Result<bool> {
    let ksp = ksp_of(snes)?;
    let mut ew = p::PetscBool::PETSC_FALSE;
    chk!(SNESKSPGetUseEW(snes, &mut ew))?;
    chk!(SNESKSPSetUseEW(snes, p::PetscBool::PETSC_FALSE))?;
    if let (p::PetscBool::PETSC_TRUE, Some(rtol)) = (ew, rtol) {
        let (_, atol, dtol, max_it) = ksp_tolerances(ksp)?;
        chk!(KSPSetTolerances(ksp, rtol, atol, dtol, max_it))?;
    }
    let solved = chk!(KSPSolve(ksp, b.raw, x.raw));
    chk!(SNESKSPSetUseEW(snes, ew))?;
    solved?;
    let mut reason = p::KSPConvergedReason(0);
    chk!(KSPGetConvergedReason(ksp, &mut reason))?;
    Ok(reason.0 > 0)
}

/// `|F(x - y)|`, infinite where the residual cannot be evaluated there.
fn full_step_norm(c: &mut Context, x: &Vector, y: &Vector) -> Result<f64, CallbackError> {
    let mut w = x.copy()?;
    w.axpy(-1.0, y)?;
    let mut f = x.duplicate()?;
    match (c.residual)(&w, &mut f) {
        Ok(()) => Ok(f.norm2()?),
        Err(CallbackError::Domain(_)) => Ok(f64::INFINITY),
        Err(e) => Err(e),
    }
}

/// The field split `pc` is (of type `pc_type`), or the first one among its parts when it is a
/// composite; `None` without one.
fn fieldsplit_within(pc: p::PC, pc_type: &str) -> Result<Option<p::PC>> {
    match pc_type {
        "fieldsplit" => Ok(Some(pc)),
        "composite" => {
            for part in composite_parts(pc, pc_type)? {
                if pc_type_name(part)? == "fieldsplit" {
                    return Ok(Some(part));
                }
            }
            Ok(None)
        }
        _ => Ok(None),
    }
}

/// PETSc's default convergence test, then the cycling of [`Snes::stop_on_cycling`].
unsafe extern "C" fn convergence_trampoline(
    snes: p::SNES,
    it: PetscInt,
    xnorm: f64,
    snorm: f64,
    fnorm: f64,
    reason: *mut p::SNESConvergedReason,
    ctx: *mut c_void,
) -> p::PetscErrorCode {
    let code = p::SNESConvergedDefault(snes, it, xnorm, snorm, fnorm, reason, std::ptr::null_mut());
    if code != 0 || ctx.is_null() || reason.is_null() {
        return code;
    }
    let cycling = &mut *(ctx as *mut Cycling);
    if it == 0 {
        cycling.last = [f64::INFINITY; 2];
        cycling.at_floor = false;
        cycling.shortened = false;
    } else {
        let code = note_shortened_step(snes, &mut cycling.shortened);
        if code != 0 {
            return code;
        }
    }
    if cycling.length > 0.0 && *reason == p::SNESConvergedReason::SNES_CONVERGED_ITERATING {
        let code = round_off_floor(snes, cycling.length, &mut cycling.floor);
        if code != 0 {
            return code;
        }
        if fnorm <= cycling.floor {
            *reason = p::SNESConvergedReason::SNES_CONVERGED_FNORM_ABS;
            cycling.at_floor = true;
            return 0;
        }
    }
    let [previous, before] = cycling.last;
    let cycles = cycling
        .progress
        .is_some_and(|least| fnorm > previous && fnorm > least * before);
    cycling.last = [fnorm, previous];
    if cycles && *reason == p::SNESConvergedReason::SNES_CONVERGED_ITERATING {
        *reason = p::SNESConvergedReason::SNES_DIVERGED_DTOL;
    }
    0
}

/// Sets `shortened` when the line search took less than the full step in the iteration just
/// done (its step length below its damping; [`SnesOutcome::shortened`]).
unsafe fn note_shortened_step(snes: p::SNES, shortened: &mut bool) -> p::PetscErrorCode {
    let mut ls: p::SNESLineSearch = std::ptr::null_mut();
    let code = p::SNESGetLineSearch(snes, &mut ls);
    if code != 0 {
        return code;
    }
    let (mut lambda, mut damping) = (1.0, 1.0);
    let code = p::SNESLineSearchGetLambda(ls, &mut lambda);
    if code != 0 {
        return code;
    }
    let code = p::SNESLineSearchGetDamping(ls, &mut damping);
    if code == 0 {
        *shortened |= lambda < damping;
    }
    code
}

/// `ROUND_OFF_FACTOR eps |K_ii|_max (length + |u|_max)` into `floor` for the solver's current
/// tangent and solution (0 before the tangent's first assembly). Collective.
unsafe fn round_off_floor(snes: p::SNES, length: f64, floor: &mut f64) -> p::PetscErrorCode {
    let (mut a, mut pmat) = (std::ptr::null_mut(), std::ptr::null_mut());
    let mut x: p::Vec = std::ptr::null_mut();
    let code = p::SNESGetJacobian(
        snes,
        &mut a,
        &mut pmat,
        std::ptr::null_mut(),
        std::ptr::null_mut(),
    );
    if code != 0 {
        return code;
    }
    let mut assembled = p::PetscBool::PETSC_FALSE;
    if a.is_null()
        || p::MatAssembled(a, &mut assembled) != 0
        || assembled != p::PetscBool::PETSC_TRUE
    {
        *floor = 0.0;
        return 0;
    }
    let code = p::SNESGetSolution(snes, &mut x);
    if code != 0 {
        return code;
    }
    let mut diagonal: p::Vec = std::ptr::null_mut();
    let (mut largest, mut u_max) = (0.0, 0.0);
    let code = p::VecDuplicate(x, &mut diagonal);
    if code != 0 {
        return code;
    }
    let mut code = p::MatGetDiagonal(a, diagonal);
    if code == 0 {
        code = p::VecNorm(diagonal, p::NormType::NORM_INFINITY, &mut largest);
    }
    let destroyed = p::VecDestroy(&mut diagonal);
    if code != 0 || destroyed != 0 {
        return if code != 0 { code } else { destroyed };
    }
    let code = p::VecNorm(x, p::NormType::NORM_INFINITY, &mut u_max);
    if code != 0 {
        return code;
    }
    *floor = ROUND_OFF_FACTOR * f64::EPSILON * largest * (length + u_max);
    0
}

/// PETSc's name of a converged reason.
fn reason_name(r: i32) -> &'static str {
    match r {
        2 => "CONVERGED_FNORM_ABS",
        3 => "CONVERGED_FNORM_RELATIVE",
        4 => "CONVERGED_SNORM_RELATIVE",
        5 => "CONVERGED_ITS",
        0 => "CONVERGED_ITERATING",
        -1 => "DIVERGED_FUNCTION_DOMAIN",
        -2 => "DIVERGED_FUNCTION_COUNT",
        -3 => "DIVERGED_LINEAR_SOLVE",
        -4 => "DIVERGED_FNORM_NAN",
        -5 => "DIVERGED_MAX_IT",
        -6 => "DIVERGED_LINE_SEARCH",
        -7 => "DIVERGED_INNER",
        -8 => "DIVERGED_LOCAL_MIN",
        -9 => "DIVERGED_DTOL",
        -10 => "DIVERGED_JACOBIAN_DOMAIN",
        -11 => "DIVERGED_TR_DELTA",
        _ => "UNKNOWN_REASON",
    }
}
