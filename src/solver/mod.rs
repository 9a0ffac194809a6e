//! Load stepping with Newton (PETSc SNES), step cutting, and per-step output.
//!
//! The load factor t goes from 0 to 1 in `steps.count` equal increments. Each increment is one
//! SNES solve of `F(u; t) = 0` from the previous converged state. A solve that does not converge
//! (diverged Newton, line-search failure, an inverted element reported as a domain error, NaN) is
//! **cut**: the state is restored and the increment halved, at most `steps.max_cuts` times in a
//! row and never below `1 / (steps.count 2^max_cuts)`; after a converged cut increment the step
//! size doubles back toward the nominal one. Every cut is reported on rank 0 and counted in the
//! history and summary. When a run fails, every output describes the last converged step.
//!
//! With frictional contact, a solve gets `FULL_STEP_ITERATIONS` full Newton steps first; if
//! they do not converge (a node's open, stick or slip state cycling), the solve is redone from
//! the same start with the `FALLBACK_LINE_SEARCH` before the step is cut. The step's Newton
//! count includes the failed attempt; the redone solves are counted in the summary
//! (`line_search_fallbacks`) and named in the progress line.
//!
//! Each step's Newton starts from the load-step predictor (`Predictor`, `steps.predictor`):
//! measured, it halves the Newton iterations of displacement-driven steps and removes the cuts
//! that a large prescribed increment otherwise causes.
//!
//! After each converged step: reactions on the constrained sets (summed over ranks), one VTU
//! file per rank, the PVTU and PVD written by rank 0 once all pieces exist, and a history row.
//! `summary.json` is rewritten after every step, so a killed run leaves a valid summary of what
//! finished (with `"converged": false`). A run stopped by SIGINT or SIGTERM
//! ([`crate::interrupt`]: polled, collectively, before every step and every Jacobian) ends
//! there: its summary keeps the finished steps and says `interrupted by ...` in `message`.

pub mod bulk;
pub mod model;
mod results;

use std::cell::RefCell;
use std::path::PathBuf;
use std::time::Instant;

use mpi::collective::{CommunicatorCollectives, Root, SystemOperation};
use mpi::topology::Communicator;

use crate::case::Scene;
use crate::contact::frictional::ContactInterfaces;
use crate::contact::tying::{Augmented, TiedInterfaces};
use crate::dofs::DofMap;
use crate::error::{print_error, print_warning, Error, Result};
use crate::interrupt;
use crate::io::output::{StepRecord, Summary};
use crate::petsc::log::Phases;
use crate::petsc::snes::Tolerances;
use crate::petsc::{CallbackError, Matrix, Petsc, Scatter, Snes, Vector};
use bulk::Bulk;
use model::DomainIssue;
use model::Model;
use results::Results;

/// At most this many Newton iterations for the stick predictor of a frictional step (it is
/// only a starting point: when it does not converge, the step starts from the load predictor).
const STICK_PREDICTOR_ITERATIONS: usize = 6;

/// Frictional contact: a solve with full Newton steps gets at most this many iterations; when it
/// does not converge (a node's stick, slip or open state cycling), the solve is redone from the
/// same start with [`FALLBACK_LINE_SEARCH`] before the step is cut.
const FULL_STEP_ITERATIONS: usize = 10;

/// The line search of the second attempt: PETSc's `l2` (a secant minimization of ||F||^2 along
/// the Newton direction). Measured on the sliding blocks: it converged every step of cases 1
/// and 2 where full steps cut steps, at 7-10 iterations per step against 2-7 for full steps; the
/// backtracking `bt` crept at 14-20.
const FALLBACK_LINE_SEARCH: &str = "l2";

/// The parts of the assembly timed apart (`summary.json` timings), in the order of
/// [`contact_seconds`]: the contact search, the mortar integration and the contact assembly of
/// the residual and tangent evaluations. `bulk_assembly` is the rest of the assembly (the
/// bulk elements, tied interfaces and PETSc's vector and matrix assembly).
const CONTACT_PHASES: [&str; 3] = ["contact_search", "contact_integration", "contact_assembly"];

/// The contact timers so far, in the order of [`CONTACT_PHASES`].
fn contact_seconds(model: &Model) -> [f64; 3] {
    let t = &model.contact.timings;
    [
        t.search.seconds(),
        t.integration.seconds(),
        t.assembly.seconds(),
    ]
}

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Folder for every result file.
    pub out_dir: PathBuf,
    /// No progress lines on rank 0.
    pub quiet: bool,
}

/// Mutable state shared by the residual and Jacobian closures.
struct EvalState {
    scatter: Scatter,
    /// Displacement of every dof this rank touches (`3 * node + c`); others stay zero.
    u: Vec<f64>,
    t: f64,
    assembly_seconds: f64,
}

impl EvalState {
    /// Fills `u` from the Newton iterate (free dofs) and the load curves (constrained dofs).
    fn load(&mut self, scene: &Scene, dofs: &DofMap, x: &Vector) -> Result<()> {
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
}

/// Runs a scene; returns the summary (also written to `summary.json`).
pub fn run(scene: &Scene, petsc: &Petsc, opts: &RunOptions) -> Result<Summary> {
    let world = petsc.world();
    let (rank, ranks) = (petsc.rank(), petsc.size());
    // Progress goes to stdout. A closed stdout ends the run with SIGPIPE (`petsc::init`); should
    // the signal be ignored after all, a failed write is no reason to stop it either.
    let say = |msg: String| {
        if rank == 0 && !opts.quiet {
            use std::io::Write;
            let _ = writeln!(std::io::stdout(), "{msg}");
        }
    };
    let mut phases = Phases::new(&["setup", "assembly", "solve", "output"])?;
    for name in CONTACT_PHASES.iter().chain(&["bulk_assembly"]) {
        phases.add(name, 0.0);
    }
    let t_setup = Instant::now();
    let setup_guard = phases.push("setup")?;

    let element_rank = partition(scene, &world, ranks)?;
    let mut dofs = DofMap::new(
        &scene.mesh,
        element_rank,
        rank,
        ranks,
        &scene.constrained_mask(),
    );
    let tying = TiedInterfaces::new(scene, &dofs, &world)?;
    let contact = ContactInterfaces::new(scene, &dofs)?;
    let mut gathered = tying.nodes();
    gathered.extend(contact.nodes());
    dofs.gather_also(&gathered);
    let mut model = Model {
        bulk: Bulk::new(scene, &dofs)?,
        tying,
        contact,
    };
    // The reference configuration is the first converged state: slip is measured from it.
    model
        .contact
        .commit(scene, &vec![0.0; 3 * scene.mesh.num_nodes()]);
    let mut sparsity = dofs.bulk_sparsity(&scene.mesh);
    model.tying.add_sparsity(&dofs, &mut sparsity);
    // Near null space for algebraic multigrid (ignored by the default direct solve).
    let rigid_modes = dofs.rigid_body_modes(&scene.mesh);
    let new_jacobian = |sparsity: &crate::petsc::Sparsity| -> Result<Matrix> {
        let mut jac = Matrix::new_aij(sparsity)?;
        jac.set_near_null_space(&rigid_modes)?;
        Ok(jac)
    };
    let mut jac = new_jacobian(&sparsity)?;
    let mut x = Vector::new_mpi(dofs.owned_count)?;
    x.set_all(0.0)?;
    let scatter = Scatter::new(&x, &dofs.gathered_global)?;
    let state = RefCell::new(EvalState {
        scatter,
        u: vec![0.0; 3 * scene.mesh.num_nodes()],
        t: 1.0,
        assembly_seconds: 0.0,
    });
    let force_scale = residual_scale(scene, &dofs, &model, &state, &x, &world)?;
    let mut snes = Snes::new(
        Tolerances {
            atol: scene.newton.atol * force_scale,
            rtol: scene.newton.rtol,
            stol: 1e-14,
            max_it: scene.newton.max_it,
        },
        &options_source(scene),
        "basic",
    )?;
    // Frictional contact: full steps first, the `l2` line search when they fail (below), unless
    // the options chose another line search.
    let fallback_line_search =
        (scene.has_friction() && snes.line_search()? == "basic").then_some(FALLBACK_LINE_SEARCH);
    if scene.is_linear() {
        snes.freeze_jacobian()?;
    }
    let mut tangent_ready = false;
    let mut newton_tangent = NewtonTangent::Other;
    let mut results = Results::new(scene, &opts.out_dir, &world)?;
    drop(setup_guard);
    phases.add("setup", t_setup.elapsed().as_secs_f64());
    say(format!(
        "mortar: {} on {ranks} rank(s): {} nodes, {} elements, {} free dofs, {} steps",
        scene.name,
        scene.mesh.num_nodes(),
        scene.mesh.num_elements(),
        dofs.total_free,
        scene.steps
    ));

    // Everything from here may fail on one rank only (I/O, say) while the others wait in a
    // collective call; such an error aborts the job *here*, while the PETSc objects are alive:
    // destroying them (MUMPS in particular) is itself collective and would hang.
    let mut summary = Summary {
        case: scene.name.clone(),
        ranks,
        converged: false,
        ..Default::default()
    };
    let stepping = (|| -> Result<()> {
        let dt_nominal = 1.0 / scene.steps as f64;
        let dt_min = dt_nominal * 0.5f64.powi(scene.max_cuts as i32) * (1.0 - 1e-12);
        let (mut t, mut dt, mut cuts_in_row, mut step) = (0.0f64, dt_nominal, 0usize, 0usize);
        let mut uzawa_capped = 0usize;
        // Contact force sums of every converged step, per interface.
        let mut contact_history: Vec<Vec<[f64; crate::contact::frictional::FORCE_SUMS]>> =
            Vec::new();
        let mut x_prev = x.duplicate()?;
        let mut x_guess = x.duplicate()?;
        let mut x_attempt = x.duplicate()?;
        let mut fallbacks = 0usize;
        // Fallbacks before the current step's first attempt (for its progress line).
        let mut fallbacks_before = 0usize;
        let mut unconverged = 0usize;
        // Newton iterations and cuts of every attempt, failed ones included (the last line).
        let (mut newton_all, mut cuts_all) = (0usize, 0usize);
        // The signal the ranks agreed to stop on (`interrupt`): at a step's start, or in a
        // Jacobian evaluation, which ends the solve under way (any later solve of the step
        // returns at once).
        let stop = std::cell::Cell::new(None);
        while t < 1.0 - 1e-12 {
            if let Some(signal) = interrupt::agreed(&world) {
                stop.set(Some(signal));
                break;
            }
            let t_new = if t + dt > 1.0 - 1e-9 { 1.0 } else { t + dt };
            if t_new <= t {
                // (The case file's bound on steps.max_cuts keeps steps far above this.)
                return Err(Error::Solve(format!(
                    "the load step {dt:.3e} no longer advances the load {} in floating point",
                    Load(t)
                )));
            }
            x.copy_to(&mut x_prev)?;
            if !model.contact.is_empty() {
                // The contact stencils of this step (pairs within a margin): a new matrix when
                // the pattern grew.
                let mut st = state.borrow_mut();
                st.t = t;
                st.load(scene, &dofs, &x)?;
                let grew = model
                    .contact
                    .add_sparsity(scene, &dofs, &st.u, &mut sparsity);
                let mut any = 0i32;
                world.all_reduce_into(&(grew as i32), &mut any, SystemOperation::max());
                if any > 0 {
                    jac = new_jacobian(&sparsity)?;
                    jac.allow_new_nonzeros()?;
                    newton_tangent = NewtonTangent::Other;
                }
            }
            let contact_saved = model.contact.save();
            state.borrow_mut().assembly_seconds = 0.0;
            // The contact work of this step's evaluations, the predictor's included (the rest of
            // `assembly` is `bulk_assembly`).
            let contact_before = contact_seconds(&model);
            let t_solve = Instant::now();
            if scene.predictor {
                let p = Predictor {
                    scene,
                    dofs: &dofs,
                    model: &model,
                    state: &state,
                    world: &world,
                };
                let reuse = scene.predictor_reuses_newton_tangent
                    && newton_tangent == NewtonTangent::OfLastConvergedStep;
                p.apply(
                    &mut x,
                    &mut jac,
                    &mut snes,
                    (t, t_new),
                    &mut tangent_ready,
                    reuse,
                )?;
            }
            state.borrow_mut().t = t_new;
            let assembly_stage = phases.stage("assembly");
            let solve_guard = phases.push("solve")?;
            let multipliers = model.tying.multipliers();
            let (mut augmentations, mut newton_total, mut linear_total) = (0usize, 0usize, 0usize);
            // One SNES solve of the current model from `x` (the closures borrow the model, so
            // they are made afresh for every solve).
            let solve_once = |snes: &mut Snes,
                              x: &mut Vector,
                              jac: &mut Matrix,
                              model: &Model|
             -> Result<crate::petsc::snes::SnesOutcome> {
                if let Some(signal) = stop.get() {
                    return Ok(not_started(signal));
                }
                let mut residual = |xv: &Vector, f: &mut Vector| -> Result<(), CallbackError> {
                    let _stage = assembly_stage.map(|st| st.push()).transpose()?;
                    let mut s = state.borrow_mut();
                    let t0 = Instant::now();
                    s.load(scene, &dofs, xv)?;
                    let inv = model.residual(scene, &dofs, &s.u, s.t, f)?;
                    s.assembly_seconds += t0.elapsed().as_secs_f64();
                    collective_domain_check(&world, inv)
                };
                let mut jacobian = |xv: &Vector, j: &mut Matrix| -> Result<(), CallbackError> {
                    // Once per Newton iteration, before its costly part. As a domain error,
                    // SNES ends the solve cleanly (not converged); the step loop stops on it.
                    if let Some(signal) = interrupt::agreed(&world) {
                        stop.set(Some(signal));
                        let name = interrupt::name(signal);
                        return Err(CallbackError::Domain(format!("interrupted by {name}")));
                    }
                    let _stage = assembly_stage.map(|st| st.push()).transpose()?;
                    let mut s = state.borrow_mut();
                    let t0 = Instant::now();
                    s.load(scene, &dofs, xv)?;
                    let inv = model.jacobian(scene, &dofs, &s.u, s.t, j)?;
                    s.assembly_seconds += t0.elapsed().as_secs_f64();
                    collective_domain_check(&world, inv)
                };
                snes.solve(x, jac, &mut residual, &mut jacobian)
            };
            if scene.stick_predictor && model.contact.has_friction() {
                // The stick predictor (see `contact::frictional`): solve with every pressed
                // node sticking, then release the Coulomb law from there.
                x.copy_to(&mut x_guess)?;
                model.contact.set_stick_all(true);
                let max_it = snes.set_max_iterations(STICK_PREDICTOR_ITERATIONS)?;
                let pre = solve_once(&mut snes, &mut x, &mut jac, &model);
                model.contact.set_stick_all(false);
                snes.set_max_iterations(max_it)?;
                let pre = pre?;
                newton_total += pre.iterations;
                linear_total += pre.linear_iterations;
                if !pre.converged {
                    x_guess.copy_to(&mut x)?;
                }
            }
            let outcome = loop {
                let outcome = match fallback_line_search {
                    None => solve_once(&mut snes, &mut x, &mut jac, &model)?,
                    Some(line_search) => {
                        x.copy_to(&mut x_attempt)?;
                        let max_it = snes.set_max_iterations(FULL_STEP_ITERATIONS)?;
                        if max_it < FULL_STEP_ITERATIONS {
                            snes.set_max_iterations(max_it)?;
                        }
                        let first = solve_once(&mut snes, &mut x, &mut jac, &model);
                        snes.set_max_iterations(max_it)?;
                        let first = first?;
                        if first.converged || stop.get().is_some() {
                            first
                        } else {
                            newton_total += first.iterations;
                            linear_total += first.linear_iterations;
                            fallbacks += 1;
                            x_attempt.copy_to(&mut x)?;
                            snes.set_line_search(line_search)?;
                            let second = solve_once(&mut snes, &mut x, &mut jac, &model);
                            snes.set_line_search("basic")?;
                            second?
                        }
                    }
                };
                newton_total += outcome.iterations;
                linear_total += outcome.linear_iterations;
                if !outcome.converged || (model.tying.is_empty() && model.contact.is_empty()) {
                    break outcome;
                }
                // Uzawa: augment the interfaces until their violations meet the tolerances.
                state.borrow_mut().load(scene, &dofs, &x)?;
                let s = state.borrow();
                let (augmented, violation) = model.augment(scene, &s.u, augmentations, &world);
                match augmented {
                    Augmented::Converged => break outcome,
                    Augmented::CapReached => {
                        uzawa_capped += 1;
                        if rank == 0 {
                            print_warning(format_args!(
                                "step {} (load {}): an interface is still \
                                 above its Uzawa tolerances after uzawa_max = {augmentations} \
                                 augmentations (tied relative gap {:.3e}; contact: \
                                 {violation:.3e} times the tolerance)",
                                step + 1,
                                Load(t_new),
                                model.tying.max_relative_gap(&s.u, &world)
                            ));
                        }
                        break outcome;
                    }
                    Augmented::Updated => augmentations += 1,
                }
                // The new multipliers change the residual by little once the gap is small:
                // still take one Newton step, so that the displacements follow.
                snes.force_iteration(true)?;
            };
            snes.force_iteration(false)?;
            drop(solve_guard);
            newton_all += newton_total;
            let assembly = state.borrow().assembly_seconds;
            let solve_seconds = t_solve.elapsed().as_secs_f64();
            phases.add("assembly", assembly);
            phases.add("solve", (solve_seconds - assembly).max(0.0));
            // The contact work of this solve's evaluations, and the bulk (the rest of them).
            let contact_now = contact_seconds(&model);
            let mut contact_total = 0.0;
            for (name, (now, before)) in CONTACT_PHASES
                .iter()
                .zip(contact_now.iter().zip(&contact_before))
            {
                phases.add(name, now - before);
                contact_total += now - before;
            }
            phases.add("bulk_assembly", (assembly - contact_total).max(0.0));
            // (The predictor's factorization counts: a linear scene may need no Newton step.)
            let null_pivots = snes.null_pivots()?;
            if let Some(n) = null_pivots.filter(|&n| n > 0) {
                return Err(Error::Solve(format!(
                    "the tangent stiffness is singular ({n} null pivot(s) at load {}): a \
                     body can move rigidly (constrain it: dirichlet or symmetry sets), or the \
                     input degrades the tangent (too low a quadrature_degree, an extreme \
                     penalty or load)",
                    Load(t_new)
                )));
            }
            let mut accepted_unconverged = false;
            if !outcome.converged && stop.get().is_some() {
                // Stopped by a signal: the run ends at the last finished step, as a failed
                // one does.
                x_prev.copy_to(&mut x)?;
                model.tying.set_multipliers(&multipliers);
                model.contact.restore(&contact_saved);
                break;
            }
            if !outcome.converged {
                let why = outcome
                    .domain_error
                    .clone()
                    .unwrap_or_else(|| outcome.reason.to_string());
                // Which limit, if any, stops the step from being cut again, in words.
                let limit =
                    cut_limit(cuts_in_row, scene.max_cuts, dt, dt_min).map(|limit| match limit {
                        CutLimit::CutsInRow => format!("no cuts left ({} allowed)", scene.max_cuts),
                        CutLimit::SmallestStep => format!(
                            "the step ({dt:.3e} of the load) is the smallest allowed \
                             (steps.max_cuts = {})",
                            scene.max_cuts
                        ),
                    });
                let giving_up = limit.is_some();
                // `steps.on_failure = "continue"`: with no cut left, a state Newton reached
                // inside the domain is the step's (unconverged) result.
                accepted_unconverged = giving_up
                    && scene.continue_on_failure
                    && outcome.domain_error.is_none()
                    && x.norm2()?.is_finite();
                if !accepted_unconverged {
                    newton_tangent = NewtonTangent::Other;
                    cuts_in_row += 1;
                    cuts_all += 1;
                    x_prev.copy_to(&mut x)?;
                    model.tying.set_multipliers(&multipliers);
                    model.contact.restore(&contact_saved);
                    let load_new = Load(t_new);
                    say(format!(
                        "  step {} load {load_new:.6}: not converged ({why}) after {} Newton its; {}",
                        step + 1,
                        outcome.iterations,
                        match &limit {
                            Some(limit) => limit.clone(),
                            None => format!("cut {cuts_in_row}/{}", scene.max_cuts),
                        }
                    ));
                    if let Some(limit) = limit {
                        summary.message = Some(format!(
                            "step {} (load {}) did not converge after {} cut(s), {limit}: {why}",
                            step + 1,
                            Load(t_new),
                            cuts_in_row - 1
                        ));
                        break;
                    }
                    dt *= 0.5;
                    continue;
                }
            }
            // The factorization the solver holds now: the last Newton iteration's of the step's
            // final, converged solve when it took one (after the predictor's and any failed
            // attempt's), else another.
            newton_tangent = if outcome.converged && outcome.iterations > 0 {
                NewtonTangent::OfLastConvergedStep
            } else {
                NewtonTangent::Other
            };
            step += 1;
            t = t_new;
            let t_out = Instant::now();
            let output_guard = phases.push("output")?;
            state.borrow_mut().load(scene, &dofs, &x)?;
            let s = state.borrow();
            let reactions = results.reactions(scene, &model, &s.u, t, &world)?;
            let contact_forces = model.contact.force_sums(scene, &s.u, &world);
            let tracked = results.tracked(scene, &dofs, &s.u, &world);
            contact_history.push(contact_forces.clone());
            let write_vtu = scene.vtu_every > 0 && (step % scene.vtu_every == 0 || t >= 1.0);
            if write_vtu {
                results.write_step(scene, &dofs, &model, &s.u, step, t, &world)?;
            }
            drop(s);
            let final_res = outcome.residual_history.last().copied().unwrap_or(0.0);
            if write_vtu {
                results.write_interfaces(scene, &model, &s_u(&state), step, t, &world);
            }
            results.push_history(&results::StepRow {
                step,
                load: t,
                newton_its: newton_total,
                augmentations,
                cuts: cuts_in_row,
                converged: outcome.converged,
                linear_its: linear_total,
                residual: final_res,
                reactions: &reactions,
                u: &s_u(&state),
                tracked: &tracked,
                contact_forces: &contact_forces,
                seconds: [
                    assembly,
                    (solve_seconds - assembly).max(0.0),
                    t_out.elapsed().as_secs_f64(),
                ],
            });
            model.contact.commit(scene, &s_u(&state));
            summary.steps.push(StepRecord {
                step,
                load: t,
                newton_its: newton_total,
                cut: cuts_in_row,
                converged: outcome.converged,
                augmentations,
            });
            drop(output_guard);
            phases.add("output", t_out.elapsed().as_secs_f64());
            if rank == 0 {
                summary.timings = phases.timings();
                results.write_summary(&summary);
            }
            results.agree(&world)?;
            // Reported once the step's files are written: a run stopped by its reader (a
            // closed stdout) has the step on disk.
            let load = Load(t);
            if accepted_unconverged {
                unconverged += 1;
                say(format!(
                    "  step {step} load {load:.6}: NOT converged ({}) after {newton_total} Newton \
                     its, |F| {final_res:.3e}; accepted (steps.on_failure = \"continue\")",
                    outcome.reason
                ));
            }
            say(format!(
                "  step {step} load {load:.6}: {newton_total} Newton its{}, |F| {final_res:.3e}, {} linear its{}, {:.2} s",
                if augmentations > 0 { format!(" ({augmentations} Uzawa augmentations)") } else { String::new() },
                linear_total,
                retries_note(cuts_in_row, fallbacks - fallbacks_before, fallback_line_search),
                solve_seconds
            ));
            cuts_in_row = 0;
            fallbacks_before = fallbacks;
            dt = (2.0 * dt).min(dt_nominal);
        }
        summary.completed = t >= 1.0 - 1e-12;
        summary.converged = summary.completed && unconverged == 0;
        let interrupted = stop.get().map(interrupt::name);
        if let Some(signal) = &interrupted {
            summary.message = Some(interruption(signal, &summary, &opts.out_dir));
        }
        // Results describe the last converged state (x was restored after a failed attempt).
        {
            let mut s = state.borrow_mut();
            s.t = t;
            s.load(scene, &dofs, &x)?;
        }
        let s = state.borrow();
        results.write_displacements(scene, &dofs, &s.u, &world);
        for (k, v) in results.metrics(scene, &dofs, &model, &s.u, &world)? {
            summary.metrics.insert(k, v);
        }
        for tied in &model.tying.interfaces {
            let area: f64 = tied.passes[0].rows.iter().map(|r| r.area).sum();
            summary
                .metrics
                .insert(format!("interface_area_{}", tied.name), area);
            for (kind, count) in &tied.stats {
                summary
                    .metrics
                    .insert(format!("pairs_{}_{kind}", tied.name), *count as f64);
            }
        }
        for (k, v) in contact_summary(&model.contact, &contact_history, &world) {
            summary.metrics.insert(k, v);
        }
        if !model.tying.is_empty() || !model.contact.is_empty() {
            summary
                .metrics
                .insert("uzawa_capped_steps".into(), uzawa_capped as f64);
            if fallback_line_search.is_some() {
                summary
                    .metrics
                    .insert("line_search_fallbacks".into(), fallbacks as f64);
            }
            if !model.tying.is_empty() {
                let gap = model.tying.max_relative_gap(&s.u, &world);
                summary.metrics.insert("max_relative_gap".into(), gap);
            }
            let most = summary
                .steps
                .iter()
                .map(|s| s.augmentations)
                .max()
                .unwrap_or(0);
            summary
                .metrics
                .insert("max_augmentations_per_step".into(), most as f64);
        }
        if scene.continue_on_failure {
            summary
                .metrics
                .insert("unconverged_steps".into(), unconverged as f64);
        }
        let newton: Vec<usize> = summary.steps.iter().map(|s| s.newton_its).collect();
        summary.metrics.insert(
            "max_newton_its".into(),
            newton.iter().copied().max().unwrap_or(0) as f64,
        );
        summary.metrics.insert(
            "total_newton_its".into(),
            newton.iter().sum::<usize>() as f64,
        );
        summary
            .metrics
            .insert("free_dofs".into(), dofs.total_free as f64);
        summary.timings = phases.timings();
        if rank == 0 {
            results.write_summary(&summary);
        }
        results.agree(&world)?;
        say(format!(
            "mortar: {}: {} -> {}",
            match (summary.completed, unconverged) {
                (true, 0) => "converged".to_string(),
                (true, n) => format!(
                    "completed with {n} unconverged step(s) accepted (steps.on_failure = \"continue\")"
                ),
                (false, _) if interrupted.is_some() => "interrupted".to_string(),
                (false, _) => "FAILED".to_string(),
            },
            totals(
                &summary,
                [newton_all, cuts_all],
                t_setup.elapsed().as_secs_f64()
            ),
            opts.out_dir.display()
        ));
        match &summary.message {
            Some(m) if interrupted.is_some() => Err(Error::Interrupted(m.clone())),
            Some(m) if !summary.completed => Err(Error::Solve(m.clone())),
            _ => Ok(()),
        }
    })();
    match stepping {
        Ok(()) => Ok(summary),
        Err(e) if ranks > 1 && !e.is_collective() => {
            print_error(crate::error::abort_line(rank as i32, &e));
            world.abort(1)
        }
        Err(e) => {
            // An error that ended the run before its summary said so (a singular tangent, a
            // failed write, an option PETSc reads at the first factorization): the summary
            // says it, with the steps finished (best effort: the error may be a full disk).
            if summary.message.is_none() {
                // (The error may come after a complete load path: the run still failed.)
                summary.converged = false;
                summary.message = Some(e.to_string());
                summary.timings = phases.timings();
                if rank == 0 {
                    results.write_summary(&summary);
                }
            }
            Err(e)
        }
    }
}

/// What stops a failed step from being cut again.
#[derive(Debug, PartialEq)]
enum CutLimit {
    /// `steps.max_cuts` cuts in a row.
    CutsInRow,
    /// The step is the nominal one halved `max_cuts` times: bounded in depth, not only in a
    /// row, so that fail and converge cycles cannot shrink it further.
    SmallestStep,
}

/// The limit a failed step of size `dt` meets after `cuts_in_row` cuts in a row (`dt_min`: the
/// smallest step allowed, a hair below the nominal one halved `max_cuts` times), if any.
fn cut_limit(cuts_in_row: usize, max_cuts: usize, dt: f64, dt_min: f64) -> Option<CutLimit> {
    if cuts_in_row + 1 > max_cuts {
        Some(CutLimit::CutsInRow)
    } else if 0.5 * dt < dt_min {
        Some(CutLimit::SmallestStep)
    } else {
        None
    }
}

/// The run's totals for its last progress line: `50 steps, 160 Newton its, 2 cuts, 4.21 s`
/// (`[newton, cuts]` of every attempt, failed ones included; cuts and the Uzawa augmentations
/// of the finished steps when there were any).
fn totals(summary: &Summary, [newton, cuts]: [usize; 2], seconds: f64) -> String {
    let count = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let mut parts = vec![
        count(summary.steps.len(), "step"),
        format!("{newton} Newton its"),
    ];
    if cuts > 0 {
        parts.push(count(cuts, "cut"));
    }
    let augmentations: usize = summary.steps.iter().map(|s| s.augmentations).sum();
    if augmentations > 0 {
        parts.push(count(augmentations, "Uzawa augmentation"));
    }
    parts.push(format!("{seconds:.2} s"));
    parts.join(", ")
}

/// The outcome of a solve not started because the run is stopping on `signal`.
fn not_started(signal: i32) -> crate::petsc::snes::SnesOutcome {
    crate::petsc::snes::SnesOutcome {
        converged: false,
        reason: "INTERRUPTED",
        iterations: 0,
        linear_iterations: 0,
        residual_history: Vec::new(),
        domain_error: Some(format!("interrupted by {}", interrupt::name(signal))),
    }
}

/// What a run stopped by `signal` (its name) leaves: `interrupted by SIGINT after step 20 (load
/// 0.4): ...`.
fn interruption(signal: &str, summary: &Summary, out_dir: &std::path::Path) -> String {
    match summary.steps.last() {
        Some(last) => format!(
            "interrupted by {signal} after step {} (load {:.6}): the outputs in {} hold the {} \
             step(s) finished",
            last.step,
            Load(last.load),
            out_dir.display(),
            summary.steps.len()
        ),
        None => format!("interrupted by {signal} before the first step finished"),
    }
}

/// Contact figures of a run: the segment-pair counts of the last evaluation
/// (`pairs_<name>_<kind>`, summed over ranks) and, for frictional interfaces,
/// `slip_force_ratio_<name>`: the mean of tangential / (mu normal) contact force over the steps
/// in which every pressed node slips (also as `slip_force_ratio` when the scene has one
/// frictional interface).
fn contact_summary(
    contact: &ContactInterfaces,
    history: &[Vec<[f64; crate::contact::frictional::FORCE_SUMS]>],
    world: &mpi::topology::SimpleCommunicator,
) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let frictional: Vec<usize> = (0..contact.interfaces.len())
        .filter(|&i| contact.interfaces[i].mu > 0.0)
        .collect();
    for (i, iface) in contact.interfaces.iter().enumerate() {
        let stats = iface.stats.borrow().to_map();
        let vals: Vec<u64> = stats.values().map(|&v| v as u64).collect();
        let mut sums = vec![0u64; vals.len()];
        world.all_reduce_into(&vals[..], &mut sums[..], SystemOperation::sum());
        for (kind, v) in stats.keys().zip(sums) {
            out.push((format!("pairs_{}_{kind}", iface.name), v as f64));
        }
        if iface.mu > 0.0 {
            let ratios: Vec<f64> = history
                .iter()
                .map(|step| step[i])
                .filter(|f| f[5] == 0.0 && f[6] > 0.0 && f[0] > 0.0)
                .map(|f| f[1] / (iface.mu * f[0]))
                .collect();
            if !ratios.is_empty() {
                let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
                out.push((format!("slip_force_ratio_{}", iface.name), mean));
                if frictional.len() == 1 {
                    out.push(("slip_force_ratio".into(), mean));
                }
            }
        }
    }
    out
}

/// The progress line's note on a step's cuts and line-search retries (empty when none).
fn retries_note(cuts: usize, retries: usize, line_search: Option<&str>) -> String {
    let mut parts = Vec::new();
    if cuts > 0 {
        parts.push(format!("{cuts} cut(s)"));
    }
    if retries > 0 {
        parts.push(format!(
            "{retries} retry(ies) with {}",
            line_search.unwrap_or_default()
        ));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(", after {}", parts.join(" and "))
    }
}

/// What the linear solver's factorization holds when a step begins (for the predictor's
/// `steps.predictor_tangent = "last_newton"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NewtonTangent {
    /// The tangent of the last Newton iteration of the last step, which converged.
    OfLastConvergedStep,
    /// Anything else: nothing yet, a failed attempt's, an unconverged step's, a step whose
    /// final solve took no Newton iteration (the factorization is then an earlier solve's), or
    /// a new matrix.
    Other,
}

/// The consistent load-step predictor.
///
/// From the converged state x_n at t_n, the first Newton iterate of the step to t_{n+1} is
/// `x_0 = x_n - K(x_n; t_n)^-1 [ F(x_n; t_n) + dF/dt (t_{n+1} - t_n) ]`: the increment of every
/// load and prescribed displacement enters linearized, through the tangent of the converged
/// state, instead of all at once into the boundary layer of elements (where a large prescribed
/// increment can invert elements on the first iterate). `dF/dt` is a one-sided difference with
/// `t_n + 1e-6 (t_{n+1} - t_n)`; loads are linear in their curves, prescribed displacements enter
/// nonlinearly, and the predictor is only a starting point for Newton, so its accuracy is
/// ample. For a pure load increment it equals the first Newton step.
///
/// With `steps.predictor_tangent = "last_newton"` (the default) the solve reuses the
/// factorization of the last step's last Newton iteration, `K(x_n^(k-1))`, as PETSc's linear
/// solver still holds it (the matrix is untouched since, so nothing is refactorized): no
/// assembly and no factorization, a prediction that differs from the consistent one by the
/// effect of the last Newton correction on the tangent. It is used only when that
/// factorization is one of the last step's converged Newton solve ([`NewtonTangent`]).
struct Predictor<'a> {
    scene: &'a Scene,
    dofs: &'a DofMap,
    model: &'a Model,
    state: &'a RefCell<EvalState>,
    world: &'a mpi::topology::SimpleCommunicator,
}

impl Predictor<'_> {
    /// Moves `x` from x_n to the predicted x_0; leaves it unchanged when the tangent or the
    /// residual at x_n is not available (an inverted element: Newton will report it).
    ///
    /// `tangent_ready` marks a constant tangent (a linear scene) already assembled in `jac`: it
    /// is then neither reassembled nor refactorized; `reuse_newton_tangent` marks the last
    /// Newton factorization as the one to solve with (the type's docs).
    fn apply(
        &self,
        x: &mut Vector,
        jac: &mut Matrix,
        snes: &mut Snes,
        (t0, t1): (f64, f64),
        tangent_ready: &mut bool,
        reuse_newton_tangent: bool,
    ) -> Result<()> {
        const EPS: f64 = 1e-6;
        let f0 = self.residual_at(x, t0)?;
        let f1 = self.residual_at(x, t0 + EPS * (t1 - t0))?;
        let (Some(f0), Some(mut rhs)) = (f0, f1) else {
            return Ok(());
        };
        // rhs = f0 + (f1 - f0) / eps
        rhs.axpy(-1.0, &f0)?;
        rhs.scale(1.0 / EPS)?;
        rhs.axpy(1.0, &f0)?;
        if !*tangent_ready && !reuse_newton_tangent {
            let mut s = self.state.borrow_mut();
            let started = Instant::now();
            s.t = t0;
            s.load(self.scene, self.dofs, x)?;
            let inv = self.model.jacobian(self.scene, self.dofs, &s.u, t0, jac)?;
            s.assembly_seconds += started.elapsed().as_secs_f64();
            if collective_domain_check(self.world, inv).is_err() {
                return Ok(());
            }
            *tangent_ready = self.scene.is_linear();
        }
        let mut dx = x.duplicate()?;
        dx.set_all(0.0)?;
        let solved = snes.linear_solve(jac, &rhs, &mut dx)?;
        if *tangent_ready {
            // The factorization just made is the one Newton would make: keep it for good.
            snes.reuse_jacobian()?;
        }
        if solved {
            x.axpy(-1.0, &dx)?;
        }
        Ok(())
    }

    /// F(x; t), or None if an element is inverted there.
    fn residual_at(&self, x: &Vector, t: f64) -> Result<Option<Vector>> {
        let mut f = x.duplicate()?;
        let mut s = self.state.borrow_mut();
        let started = Instant::now();
        s.t = t;
        s.load(self.scene, self.dofs, x)?;
        let inv = self
            .model
            .residual(self.scene, self.dofs, &s.u, t, &mut f)?;
        s.assembly_seconds += started.elapsed().as_secs_f64();
        Ok(collective_domain_check(self.world, inv).ok().map(|_| f))
    }
}

/// A copy of the current displacements.
fn s_u(state: &RefCell<EvalState>) -> Vec<f64> {
    state.borrow().u.clone()
}

/// Where PETSc's options came from, for messages: the command line, the scene's options file,
/// and a study variant's `petsc` while one is set.
fn options_source(scene: &Scene) -> String {
    let mut sources = vec!["command line".to_string()];
    if let Some(f) = &scene.petsc_options {
        sources.push(f.display().to_string());
    }
    if crate::petsc::options::overridden() {
        sources.push("the study variant's `petsc`".into());
    }
    let n = sources.len();
    if n == 1 {
        sources.remove(0)
    } else {
        format!("{} or {}", sources[..n - 1].join(", "), sources[n - 1])
    }
}

/// Rank 0 partitions the elements with METIS; every rank receives the same partition.
fn partition(
    scene: &Scene,
    world: &mpi::topology::SimpleCommunicator,
    ranks: usize,
) -> Result<Vec<usize>> {
    let n = scene.mesh.num_elements();
    let mut parts = vec![0u64; n];
    if ranks > 1 {
        if world.rank() == 0 {
            let p = crate::mesh::partition::partition_elements(&scene.mesh, ranks)?;
            parts.iter_mut().zip(p).for_each(|(a, b)| *a = b as u64);
        }
        world.process_at_rank(0).broadcast_into(&mut parts[..]);
    }
    Ok(parts.into_iter().map(|p| p as usize).collect())
}

/// Turns a local domain issue (an inverted element, a failed contact evaluation) into the same
/// domain error on every rank.
fn collective_domain_check(
    world: &mpi::topology::SimpleCommunicator,
    issue: Option<DomainIssue>,
) -> Result<(), CallbackError> {
    // The lowest inverted element of all ranks (each rank's first is its lowest: elements are
    // visited in ascending order), with its det F from its owner; else the contact failure of
    // the lowest rank that has one: the message does not depend on the partition.
    let element = match &issue {
        Some(DomainIssue::Inverted(i)) => i.element as i64,
        _ => i64::MAX,
    };
    let mut lowest = i64::MAX;
    world.all_reduce_into(&element, &mut lowest, SystemOperation::min());
    if lowest != i64::MAX {
        let det = match &issue {
            Some(DomainIssue::Inverted(i)) if i.element as i64 == lowest => i.det,
            _ => 0.0,
        };
        let mut owner_det = 0.0;
        world.all_reduce_into(&det, &mut owner_det, SystemOperation::sum());
        return Err(CallbackError::Domain(format!(
            "element {lowest} inverted (det F = {owner_det:.3e})"
        )));
    }
    let mine = match &issue {
        Some(DomainIssue::Contact(m)) => Some(m.as_str()),
        _ => None,
    };
    match first_rank_text(world, mine) {
        Some(m) => Err(CallbackError::Domain(format!("contact: {m}"))),
        None => Ok(()),
    }
}

/// Collective: the lowest rank for which `flag` holds, or the number of ranks if none.
pub fn lowest_rank_with(world: &mpi::topology::SimpleCommunicator, flag: bool) -> i32 {
    use mpi::traits::Communicator;
    let mine = if flag { world.rank() } else { world.size() };
    let mut lowest = 0;
    world.all_reduce_into(&mine, &mut lowest, SystemOperation::min());
    lowest
}

/// Collective: the `text` of the lowest rank that has one, on every rank (`None` when no rank
/// has one).
pub(crate) fn first_rank_text(
    world: &mpi::topology::SimpleCommunicator,
    text: Option<&str>,
) -> Option<String> {
    use mpi::traits::{Communicator, Root};
    let first = lowest_rank_with(world, text.is_some());
    if first == world.size() {
        return None;
    }
    let mut bytes = match text {
        Some(t) if world.rank() == first => t.as_bytes().to_vec(),
        _ => Vec::new(),
    };
    let root = world.process_at_rank(first);
    let mut len = bytes.len() as u64;
    root.broadcast_into(&mut len);
    bytes.resize(len as usize, 0);
    root.broadcast_into(&mut bytes[..]);
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

/// Collective: every rank returns `Ok` when `mine` is `Ok` on every rank, else the error of the
/// lowest failing rank as [`Error::Output`] (its message sent to all).
pub(crate) fn agree_on(world: &mpi::topology::SimpleCommunicator, mine: Result<()>) -> Result<()> {
    let message = mine.err().map(|e| e.to_string());
    match first_rank_text(world, message.as_deref()) {
        Some(m) => Err(Error::Output(m)),
        None => Ok(()),
    }
}

/// The norm of the residual at u = 0 under the full load: the force scale of the absolute
/// Newton tolerance (1 if the scene is unloaded).
fn residual_scale(
    scene: &Scene,
    dofs: &DofMap,
    model: &Model,
    state: &RefCell<EvalState>,
    x: &Vector,
    world: &mpi::topology::SimpleCommunicator,
) -> Result<f64> {
    let mut f = x.duplicate()?;
    let mut s = state.borrow_mut();
    s.t = 1.0;
    s.load(scene, dofs, x)?;
    let inv = model.residual(scene, dofs, &s.u, 1.0, &mut f)?;
    let mut any: i64 = 0;
    world.all_reduce_into(&(inv.is_some() as i64), &mut any, SystemOperation::max());
    let norm = if any > 0 { 0.0 } else { f.norm2()? };
    s.u.iter_mut().for_each(|v| *v = 0.0);
    Ok(if norm.is_finite() && norm > 0.0 {
        norm
    } else {
        1.0
    })
}

/// A load factor in messages and progress lines: as asked (`{:.6}`), or with `{}` to 12
/// decimals without trailing zeros (the load accumulates its steps, `0.1 + 0.2` reads `0.3`,
/// not `0.30000000000000004`), or in scientific notation when it is tiny (a step cut many
/// times), where the plain forms would run to a hundred digits or show only zeros.
struct Load(f64);

impl std::fmt::Display for Load {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = self.0 + 0.0; // (-0 prints as 0)
        match f.precision() {
            _ if t != 0.0 && t.abs() < 1e-4 => write!(f, "{t:.6e}"),
            Some(digits) => write!(f, "{t:.digits$}"),
            None => {
                let fixed = format!("{t:.12}");
                write!(f, "{}", fixed.trim_end_matches('0').trim_end_matches('.'))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{cut_limit, CutLimit, Load};

    /// `steps.max_cuts = 2`, nominal step 0.01: a step cut twice in a row has no cut left; a
    /// step at a quarter of the nominal one after one cut in a row (cut twice before, then
    /// converged and grown back by one doubling) is at the smallest size instead (the sliding
    /// blocks' case 5 of Figure 7 ends so).
    #[test]
    fn a_failed_step_meets_the_limit_it_reached() {
        let (nominal, max_cuts) = (0.01, 2);
        let dt_min = nominal * 0.25 * (1.0 - 1e-12);
        let limit = |cuts, dt| cut_limit(cuts, max_cuts, dt, dt_min);
        assert_eq!(limit(0, nominal), None);
        assert_eq!(limit(1, nominal / 2.0), None);
        assert_eq!(limit(2, nominal / 4.0), Some(CutLimit::CutsInRow));
        assert_eq!(limit(2, nominal), Some(CutLimit::CutsInRow));
        assert_eq!(limit(1, nominal / 4.0), Some(CutLimit::SmallestStep));
        assert_eq!(limit(0, nominal / 4.0), Some(CutLimit::SmallestStep));
        assert_eq!(cut_limit(0, 0, nominal, nominal), Some(CutLimit::CutsInRow));
    }

    #[test]
    fn loads_print_as_asked_unless_tiny() {
        assert_eq!(format!("{:.6}", Load(0.5)), "0.500000");
        assert_eq!(format!("{}", Load(0.15625)), "0.15625");
        assert_eq!(format!("{}", Load(0.0)), "0");
        assert_eq!(format!("{}", Load(1.0)), "1");
        assert_eq!(format!("{}", Load(0.1 + 0.2)), "0.3");
        assert_eq!(format!("{}", Load(13.0 * 0.02)), "0.26");
        assert_eq!(format!("{}", Load(-0.0)), "0");
        // A step cut 483 times: not 150 digits, not zeros.
        let tiny = 0.5f64.powi(483);
        assert_eq!(format!("{}", Load(tiny)), format!("{tiny:.6e}"));
        assert_eq!(format!("{:.6}", Load(tiny)), format!("{tiny:.6e}"));
    }
}
