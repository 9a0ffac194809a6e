//! One run of a study: variant `v` at refinement `level`, into `runs/<variant>/<level>/`,
//! measured and recorded ([`RunRecord`]).
//!
//! Every run shares one PETSc: its options are the base case's options file (no variant may
//! change `petsc_options`), the command line, and the variant's own `petsc` options, set for its
//! runs only (options a variant sets that none of its runs reads draw one warning naming the
//! variant, after its last run). A variant with `ranks = k` runs on the first k ranks of the job
//! (a split communicator); the other ranks wait for it (OpenMPI's waiting polls, so on a machine
//! with as many cores as ranks the waiting rank takes a little of the time measured).
//!
//! A run's folder is emptied before it runs, so that nothing of an earlier study in the same
//! `--out` passes for this run's. Its wall time is the fastest of its converged `repeat`s; its
//! peak memory is Linux's `VmHWM`, reset before each run, the largest over the ranks: the runs
//! share one process, so before each run the memory the earlier ones freed goes back to the OS
//! ([`Petsc::release_free_memory`]), or a run after a larger one would report that one's peak.
//!
//! A failed run (not converged, steps accepted unconverged under `steps.on_failure =
//! "continue"`, a bad value of a PETSc option, a solver package PETSc lacks: found when the run
//! sets up its solver, `ksp::probe_factorization`, ...) is recorded (`converged = false`, no
//! point on the convergence plot) and the study goes on ([`crate::study::run`]). A metric
//! missing from a converged run's summary stops the study: it would be missing from every run.
//! So does an error that need not reach every rank alike (an error PETSc raises inside a solve;
//! I/O), and a file a run cannot write (`Error::Output`, which the next runs would meet too):
//! the message names the variant and level, also when one rank of a 2-rank run meets it and
//! aborts the job (`error::with_context`).

use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

use mpi::collective::{CommunicatorCollectives, Root, SystemOperation};
use mpi::topology::Communicator;

use super::file::{Study, VariantSpec};
use super::output::RunRecord;
use crate::error::{Error, Result};
use crate::io::output::Summary;
use crate::petsc::Petsc;
use crate::solver::{self, RunOptions};

/// One run as measured: its record (the same on every rank), the variant's PETSc options that
/// nothing read in it, and whether the signal stopped it (as this rank saw it).
pub(super) struct Measured {
    pub(super) record: RunRecord,
    pub(super) unused: BTreeSet<String>,
    pub(super) interrupted: bool,
}

impl Study {
    /// Runs variant `v` at refinement `level` into `run_dir` (emptied first), with its repeats,
    /// and records it. `Err` for what ends the study (a metric the runs do not report, an
    /// error that need not reach every rank alike: see the module docs).
    pub(super) fn measure_run(
        &self,
        petsc: &Petsc,
        v: usize,
        level: usize,
        run_dir: &Path,
    ) -> Result<Measured> {
        let variant = &self.variants[v];
        fresh_run_dir(petsc, run_dir)?;
        let ranks = variant.ranks.unwrap_or(petsc.size());
        let t0 = Instant::now();
        let (result, unused) = self.run_one(petsc, v, level, run_dir)?;
        let interrupted = matches!(result, Some(Err(Error::Interrupted(_))));
        let seconds = t0.elapsed().as_secs_f64();
        let peak_memory_mb = peak_memory_over_ranks(petsc);
        let h = self.refinements[level].h;
        let mut record = RunRecord::new(&variant.name, level, h, ranks, seconds, peak_memory_mb);
        let missing_metric = self
            .record_result(&mut record, result, run_dir, petsc.rank())
            .map_err(|e| self.run_error(v, level, e))?;
        // After the broadcast, so that ranks that waited (`ranks`) stop with the others.
        if share_record(petsc, &mut record, missing_metric.is_some()) {
            return Err(Error::Case {
                file: self.file.clone(),
                msg: missing_metric.unwrap_or_default(),
            });
        }
        if record.converged && self.repeat > 1 && !self.is_reference(variant) {
            for t in self.repeat_times(petsc, v, level, run_dir, record.newton_its)? {
                record.seconds = record.seconds.min(t);
                record.seconds_slowest = record.seconds_slowest.max(t);
            }
        }
        Ok(Measured {
            record,
            unused,
            interrupted,
        })
    }

    /// Records a run's `result` (`None` on the ranks that waited) in `record`: its Newton
    /// iterations and augmentations, its error and metrics when it converged, why it failed
    /// when it did (the iterations of a failed run from its `summary.json` in `run_dir`, on
    /// rank 0). Returns the message of a metric the run does not report; `Err` with an error
    /// that ends the study ([`ends_study`]).
    fn record_result(
        &self,
        record: &mut RunRecord,
        result: Option<Result<Summary>>,
        run_dir: &Path,
        rank: usize,
    ) -> Result<Option<String>> {
        match result {
            None => {}
            Some(Ok(s)) if !s.converged => {
                record.newton_its = s.steps.iter().map(|st| st.newton_its).sum();
                record.message = s.message.clone().or_else(|| {
                    let n = s.steps.iter().filter(|st| !st.converged).count();
                    Some(format!(
                        "{n} step(s) accepted without convergence (steps.on_failure = \
                         \"continue\")"
                    ))
                });
            }
            Some(Ok(s)) => {
                record.newton_its = s.steps.iter().map(|st| st.newton_its).sum();
                record.augmentations = s.steps.iter().map(|st| st.augmentations).sum();
                match self.error_of(&s) {
                    Ok(e) if e.is_finite() => {
                        record.error = Some(e);
                        record.converged = true;
                        record.metrics = s.metrics;
                    }
                    Ok(e) => record.message = Some(format!("{} = {e}", self.metric)),
                    Err(msg) => return Ok(Some(msg)),
                }
            }
            // Errors every rank meets alike are this run's failure; any other (an I/O error on
            // one rank) and a file the run could not write end the study, as they end a run.
            Some(Err(e)) if !ends_study(&e) => {
                if rank == 0 {
                    record.newton_its = Summary::read(&run_dir.join("summary.json"))
                        .map(|s| s.steps.iter().map(|st| st.newton_its).sum())
                        .unwrap_or(0);
                }
                record.message = Some(e.to_string());
            }
            Some(Err(e)) => return Err(e),
        }
        Ok(None)
    }

    /// A converged run's error: its metric, or the largest absolute value of the metrics (NaN
    /// if one is not finite); `Err` names a metric the run does not report.
    fn error_of(&self, run: &Summary) -> std::result::Result<f64, String> {
        let mut error = 0.0f64;
        for part in &self.metric_parts {
            let Some(&e) = run.metrics.get(part) else {
                return Err(format!(
                    "metric \"{part}\": the runs do not report it (they report: {})",
                    run.metrics.keys().cloned().collect::<Vec<_>>().join(", ")
                ));
            };
            error = match self.metric_parts.len() {
                1 => e,
                _ if !e.is_finite() || error.is_nan() => f64::NAN,
                _ => error.max(e.abs()),
            };
        }
        Ok(error)
    }

    /// Runs variant `v` at refinement `level` into `run_dir`, with the variant's PETSc options
    /// and on its ranks: `None` on the ranks that wait while it runs on fewer. The error is the
    /// run's (to record); `Err` only if the variant's options cannot be set. Also returns the
    /// variant's options that nothing read in this run.
    pub(super) fn run_one(
        &self,
        petsc: &Petsc,
        v: usize,
        level: usize,
        run_dir: &Path,
    ) -> Result<(Option<Result<Summary>>, BTreeSet<String>)> {
        let ranks = self.variants[v].ranks.unwrap_or(petsc.size());
        let options = crate::petsc::options::Override::set(&self.variant_options[v])?;
        let result = crate::error::with_context(self.run_label(v, level), || {
            petsc.on_first_ranks(ranks, || {
                self.scene(v, level).and_then(|scene| {
                    solver::run(&scene, petsc, &RunOptions::new(run_dir.to_path_buf(), true))
                })
            })
        });
        let unused = options.unused().into_iter().collect();
        Ok((result, unused))
    }

    /// A variant that is never on the Pareto front, whose time is not compared: a
    /// `reference_only` one, or the `[curves]` reference.
    pub(super) fn is_reference(&self, variant: &VariantSpec) -> bool {
        variant.reference_only
            || self
                .curves
                .as_ref()
                .is_some_and(|c| c.reference == variant.name)
    }

    /// Makes the run of variant `v` at `level` `repeat - 1` more times, into a scratch folder
    /// beside `run_dir` that is removed afterwards, and returns the wall times of the repeats
    /// that converged in the first run's `newton_its` (rank 0's, on every rank: on more than
    /// one rank round-off may steer a repeat onto another Newton path, whose time is another
    /// run's).
    pub(super) fn repeat_times(
        &self,
        petsc: &Petsc,
        v: usize,
        level: usize,
        run_dir: &Path,
        newton_its: usize,
    ) -> Result<Vec<f64>> {
        let scratch = run_dir.with_extension("repeat");
        let mut times = Vec::with_capacity(self.repeat - 1);
        for _ in 1..self.repeat {
            // Collective over the whole job (every rank repeats the run).
            if crate::interrupt::agreed(&petsc.world()).is_some() {
                break;
            }
            let t0 = Instant::now();
            let (result, _) = self.run_one(petsc, v, level, &scratch)?;
            let seconds = t0.elapsed().as_secs_f64();
            let same_path = match result {
                Some(Ok(s)) => {
                    s.converged
                        && s.steps.iter().map(|st| st.newton_its).sum::<usize>() == newton_its
                }
                Some(Err(e)) if ends_study(&e) => return Err(self.run_error(v, level, e)),
                _ => false,
            };
            let mut figures = [seconds, f64::from(u8::from(same_path))];
            petsc
                .world()
                .process_at_rank(0)
                .broadcast_into(&mut figures[..]);
            if figures[1] != 0.0 {
                times.push(figures[0]);
            }
        }
        if petsc.rank() == 0 && scratch.exists() {
            std::fs::remove_dir_all(&scratch).map_err(|e| Error::io(&scratch, e))?;
        }
        Ok(times)
    }

    /// The study stopped by `signal` at `label` (its run), with `runs` finished.
    pub(super) fn interrupted(
        &self,
        signal: i32,
        label: &str,
        runs: &[RunRecord],
        out: &Path,
    ) -> Error {
        let finished = match runs.len() {
            0 => "no run finished".to_string(),
            n => format!("{n} finished run(s) in {}", out.join("study.csv").display()),
        };
        Error::Interrupted(format!(
            "interrupted by {} at {label}: {finished}",
            crate::interrupt::name(signal)
        ))
    }

    /// An error that ends the study (one that need not reach every rank alike: a PETSc
    /// error, I/O), naming the run it came from.
    pub(super) fn run_error(&self, v: usize, level: usize, e: Error) -> Error {
        Error::Other(format!("{}: {e}", self.run_label(v, level)))
    }

    /// "study F: variant 'v' at level L", for the messages of that run.
    pub(super) fn run_label(&self, v: usize, level: usize) -> String {
        format!(
            "study {}: variant '{}' at level {level}",
            self.file.display(),
            self.variants[v].name
        )
    }
}

/// Whether a run's error ends the study rather than failing the run: an error that need not
/// reach every rank alike, and a file the run could not write ([`Error::Output`]: a full disk,
/// a folder without write permission, which the next runs would meet too). It is returned as
/// a rank's own error ([`Study::run_error`]), so on several ranks the job is aborted with it,
/// whatever the other ranks are doing.
pub(super) fn ends_study(e: &Error) -> bool {
    !e.is_collective() || matches!(e, Error::Output(_))
}

/// Gives every rank rank 0's figures of a run (rank 0 runs every variant; the others may have
/// waited, and their clocks differ), so that all ranks agree on the study's outcome, and
/// returns rank 0's `fatal` (the study must stop). The failure message stays on rank 0, which
/// prints it.
fn share_record(petsc: &Petsc, r: &mut RunRecord, fatal: bool) -> bool {
    let mut figures = [
        r.error.unwrap_or(f64::NAN),
        r.seconds,
        r.newton_its as f64,
        r.augmentations as f64,
        f64::from(u8::from(r.converged)),
        f64::from(u8::from(fatal)),
    ];
    petsc
        .world()
        .process_at_rank(0)
        .broadcast_into(&mut figures[..]);
    r.error = (!figures[0].is_nan()).then_some(figures[0]);
    r.seconds = figures[1];
    r.seconds_slowest = figures[1];
    r.newton_its = figures[2] as usize;
    r.augmentations = figures[3] as usize;
    r.converged = figures[4] != 0.0;
    figures[5] != 0.0
}

/// Empties a run's folder (rank 0): in a reused output folder nothing of an earlier study's run
/// may pass for this run's (its summary, read when this run fails, or its history and VTU
/// files). Then, with every rank there, gives the memory the earlier runs freed back to the OS
/// and resets the peak.
fn fresh_run_dir(petsc: &Petsc, run_dir: &Path) -> Result<()> {
    if petsc.rank() == 0 && run_dir.exists() {
        std::fs::remove_dir_all(run_dir).map_err(|e| Error::io(run_dir, e))?;
    }
    petsc.world().barrier();
    petsc.release_free_memory();
    crate::memory::reset_peak();
    Ok(())
}

/// The peak resident memory of the run just made, the largest over the ranks (every rank takes
/// part); `None` where a rank cannot read it.
fn peak_memory_over_ranks(petsc: &Petsc) -> Option<f64> {
    // -1: not available there.
    let local = crate::memory::peak_mb().unwrap_or(-1.0);
    let mut most = 0.0f64;
    petsc
        .world()
        .all_reduce_into(&local, &mut most, SystemOperation::max());
    (most >= 0.0).then_some(most)
}
