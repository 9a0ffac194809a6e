//! Running a study ([`Study::run`]): every variant at every refinement (variant by variant,
//! the refinements in the order listed), each run measured and recorded
//! ([`crate::study::one_run`]), `study.csv` and `summary.json` rewritten after every run; once
//! every run is done, the errors against the finest run, the Pareto front, the plots and the
//! closing line ([`crate::study::output`]).
//!
//! The first run of a process pays one-time costs (loading the solver libraries, first
//! allocations): an untimed run of the first variant at the first level comes first, into
//! `<out>/warm_up/`, unless that variant is the `[curves]` reference (not on the front).
//!
//! A study stopped by SIGINT or SIGTERM ([`crate::interrupt`]) ends once the run it was in
//! stops (at its next Newton iteration; a run on fewer ranks than the job, or one of its
//! `repeat`s, may finish first), with the runs that finished in `study.csv`.
//!
//! When any run failed, the study fails after writing everything and printing its
//! expectations (checked on what the other runs measured: [`StudyReport::failure`]), unless
//! every failed run belongs to a variant with `may_fail = true` (a baseline expected to
//! break).

use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

use mpi::collective::Root;
use mpi::topology::Communicator;

use super::file::Study;
use super::finest::add_values;
use super::one_run::{ends_study, Measured};
use super::output::{progress_line, study_csv, RunRecord};
use crate::error::{print_warning, Error, Result};
use crate::io::output::{lock_folder, write_atomic, FolderLock, Summary};
use crate::petsc::Petsc;
use crate::solver::RunOptions;

/// What a study did.
#[derive(Debug)]
#[must_use = "a study whose runs failed says so in `failure`"]
pub struct StudyReport {
    pub runs: Vec<RunRecord>,
    /// The study summary (also in `summary.json`).
    pub summary: Summary,
    /// Runs failed that were not allowed to (`may_fail`), or the `finest_reference` run did:
    /// the study is done and written, and fails with this error once its expectations are
    /// printed.
    pub failure: Option<Error>,
}

impl Study {
    /// Runs every variant at every refinement (variant by variant, coarsest refinement as
    /// listed first) and writes the study's outputs in `opts.out_dir` (see the module docs).
    /// Progress (one line per run) on rank 0 unless `opts.quiet`. Runs that failed (and were
    /// not allowed to), or a `finest_reference` run that failed, do not make this an error:
    /// everything is written, and the report's [`StudyReport::failure`] holds the study's
    /// error, for the caller to return once it has checked the expectations. An error here is
    /// one that stopped the study (a bad path, an I/O error, a missing metric, ...).
    pub fn run(&self, petsc: &Petsc, opts: &RunOptions) -> Result<StudyReport> {
        let out = &opts.out_dir;
        // (Before the output folder is made: a refused study leaves nothing behind.)
        self.check_ranks(petsc.size())?;
        // The folder's lock (rank 0), held to the study's end: a second study (or run) into
        // it would empty the run folders of this one.
        let _lock = lock_out_dir(petsc, out)?;
        let mut progress = Progress {
            study: self,
            petsc,
            out,
            quiet: opts.quiet,
            started: Instant::now(),
            runs: Vec::with_capacity(self.total_runs()),
            summary: Summary::default(),
            columns_checked: self.curves.is_none(),
        };
        progress.say(format!(
            "mortar study {}: {} variant(s) x {} refinement(s) = {} runs of {} on {} \
             rank(s) -> {}",
            self.name,
            self.variants.len(),
            self.refinements.len(),
            self.total_runs(),
            self.case.display(),
            petsc.size(),
            out.display()
        ));
        self.warm_up(petsc, out)?;
        for v in 0..self.variants.len() {
            progress.run_variant(v)?;
        }
        let reference_failed = progress.errors_against_finest();
        if self.curves.is_none() {
            for i in self.front(&progress.runs) {
                progress.runs[i].on_front = true;
            }
        }
        if petsc.rank() == 0 {
            progress.write_outputs()?;
        }
        Ok(progress.report(reference_failed))
    }

    /// Refuses a variant on more ranks than the job has (`size`).
    fn check_ranks(&self, size: usize) -> Result<()> {
        let Some((i, v)) = self
            .variants
            .iter()
            .enumerate()
            .find(|(_, v)| v.ranks.is_some_and(|r| r > size))
        else {
            return Ok(());
        };
        Err(Error::Case {
            file: self.file.clone(),
            msg: format!(
                "variant[{i}].ranks = {}: the study runs on {size} rank(s) (mpirun -n {} \
                 mortar study ...)",
                v.ranks.unwrap_or(0),
                v.ranks.unwrap_or(0)
            ),
        })
    }

    /// The untimed first run (see the module docs): its failure is no failure of the study,
    /// unless it is one that ends the study.
    fn warm_up(&self, petsc: &Petsc, out: &Path) -> Result<()> {
        let first_is_reference = self
            .curves
            .as_ref()
            .is_some_and(|c| c.reference == self.variants[0].name);
        if first_is_reference {
            return Ok(());
        }
        let warm_up = out.join("warm_up");
        if let (Some(Err(e)), _) = self.run_one(petsc, 0, 0, &warm_up)? {
            if ends_study(&e) {
                return Err(self.run_error(0, 0, e));
            }
        }
        if let Some(signal) = crate::interrupt::agreed(&petsc.world()) {
            let label = format!("study {}: the warm-up run", self.file.display());
            return Err(self.interrupted(signal, &label, &[], out));
        }
        Ok(())
    }

    /// The study's failure for the runs that failed and were not allowed to (`may_fail`).
    fn runs_failed(&self, runs: &[RunRecord], out: &Path) -> Option<Error> {
        let may_fail = |r: &&RunRecord| {
            self.variants
                .iter()
                .any(|v| v.name == r.variant && v.may_fail)
        };
        let unexpected = runs.iter().filter(|r| !r.converged && !may_fail(r)).count();
        (unexpected > 0).then(|| {
            let first =
                runs.iter()
                    .find(|r| !r.converged && !may_fail(r))
                    .map_or(String::new(), |r| {
                        format!(
                            "; first: {} level {}: {}",
                            r.variant,
                            r.level,
                            r.message.as_deref().unwrap_or("not converged")
                        )
                    });
            Error::Solve(format!(
                "study {}: {unexpected} of {} runs failed (see {}){first}",
                self.name,
                self.total_runs(),
                out.join("study.csv").display()
            ))
        })
    }
}

/// Locks the output folder on rank 0 (made if need be); every rank learns whether it could.
fn lock_out_dir(petsc: &Petsc, out: &Path) -> Result<Option<FolderLock>> {
    let locked = if petsc.rank() == 0 {
        lock_folder(out)
    } else {
        Ok(None)
    };
    let (agreed, lock) = match locked {
        Ok(lock) => (Ok(()), lock),
        Err(e) => (Err(e), None),
    };
    crate::solver::agree_on(&petsc.world(), agreed)?;
    Ok(lock)
}

/// A study under way: the runs so far and the summary of them.
struct Progress<'s> {
    study: &'s Study,
    petsc: &'s Petsc,
    out: &'s Path,
    quiet: bool,
    started: Instant,
    runs: Vec<RunRecord>,
    summary: Summary,
    /// The curves' columns have been checked against a history (none to check without
    /// `[curves]`).
    columns_checked: bool,
}

impl Progress<'_> {
    /// A progress line, on rank 0 unless quiet.
    fn say(&self, msg: String) {
        if self.petsc.rank() == 0 && !self.quiet {
            println!("{msg}");
        }
    }

    /// The summary of the runs so far.
    fn current_summary(&self) -> Summary {
        let seconds = self.started.elapsed().as_secs_f64();
        self.study.summary(&self.runs, self.petsc.size(), seconds)
    }

    /// Variant `v` at every refinement; then the warning for its PETSc options that none of its
    /// runs read.
    fn run_variant(&mut self, v: usize) -> Result<()> {
        let mut unread: Option<BTreeSet<String>> = None;
        for level in 0..self.study.refinements.len() {
            let unused = self.run_level(v, level)?;
            unread = Some(match unread {
                None => unused,
                Some(before) => before.intersection(&unused).cloned().collect(),
            });
        }
        let unread = unread.unwrap_or_default();
        if self.petsc.rank() == 0 && !unread.is_empty() {
            print_warning(format_args!(
                "variant '{}': PETSc option(s) {} not used by any of its \
                 runs (a typo, or an option of a solver not in use)",
                self.study.variants[v].name,
                unread.into_iter().collect::<Vec<_>>().join(", ")
            ));
        }
        Ok(())
    }

    /// Variant `v` at refinement `level`: run, recorded (unless the signal stopped it) and
    /// written; the study stops here when a signal came. Returns the variant's options the
    /// run did not read.
    fn run_level(&mut self, v: usize, level: usize) -> Result<BTreeSet<String>> {
        let (study, petsc) = (self.study, self.petsc);
        let name = &study.variants[v].name;
        let run_dir = self.out.join("runs").join(name).join(level.to_string());
        let Measured {
            record,
            unused,
            interrupted,
        } = study.measure_run(petsc, v, level, &run_dir)?;
        // Collective over the whole job: ranks that waited out a run on fewer ranks stop with
        // the others. A run the signal stopped is left out; one that finished is recorded.
        let stop = crate::interrupt::agreed(&petsc.world());
        // Rank 0's verdict (the ranks a smaller run left out have none).
        let mut run_interrupted = i32::from(interrupted);
        petsc
            .world()
            .process_at_rank(0)
            .broadcast_into(&mut run_interrupted);
        if stop.is_none() || run_interrupted == 0 {
            self.record(record)?;
        }
        if let Some(signal) = stop {
            let label = study.run_label(v, level);
            return Err(study.interrupted(signal, &label, &self.runs, self.out));
        }
        if !self.columns_checked {
            self.columns_checked = study.check_columns(petsc, &run_dir)?;
        }
        Ok(unused)
    }

    /// Adds a finished run: its progress line, and (rank 0) `study.csv` and `summary.json`
    /// rewritten.
    fn record(&mut self, record: RunRecord) -> Result<()> {
        self.say(progress_line(&self.study.metric, &record));
        self.runs.push(record);
        if self.petsc.rank() == 0 {
            write_atomic(
                &self.out.join("study.csv"),
                study_csv(&self.runs).as_bytes(),
            )?;
            self.summary = self.current_summary();
            self.summary.write(&self.out.join("summary.json"))?;
        }
        Ok(())
    }

    /// With `finest_reference`, the metrics become errors against the finest run's
    /// ([`crate::study::finest`]); the summary (rank 0) gets the values, and is written with
    /// the Pareto front. Returns the study's failure when there is no truth.
    fn errors_against_finest(&mut self) -> Option<String> {
        let (values, failed) = self.study.against_finest(&mut self.runs)?;
        if self.petsc.rank() == 0 {
            self.summary = self.current_summary();
            add_values(&mut self.summary, &self.runs, &values);
            if failed.is_some() {
                self.summary.message.clone_from(&failed);
            }
        }
        failed
    }

    /// The outputs once every run is done (rank 0): the convergence plot, the Pareto front,
    /// the curves, `study.csv` and the summary with their flags and metrics; the closing line.
    fn write_outputs(&mut self) -> Result<()> {
        let (study, out) = (self.study, self.out);
        let mut done = Vec::new();
        if study.refinements.len() >= 2 {
            done.push(study.write_convergence(&self.runs, out)?);
        }
        match &study.curves {
            None => {
                let label = study.error_label();
                done.push(study.write_pareto(&self.runs, &label, &mut self.summary, out)?);
                write_atomic(&out.join("study.csv"), study_csv(&self.runs).as_bytes())?;
            }
            Some(curves) => done.extend(study.write_curve_outputs(
                curves,
                &mut self.runs,
                &mut self.summary,
                out,
            )?),
        }
        let total = study.total_runs();
        let failed = self.runs.iter().filter(|r| !r.converged).count();
        done.push(format!("{} of {total} runs converged", total - failed));
        self.say(format!(
            "mortar study {}: {} -> {}",
            study.name,
            done.join("; "),
            out.display()
        ));
        Ok(())
    }

    /// The report: the runs, the summary, and the study's failure (the finest reference's
    /// first: without it no run has an error).
    fn report(self, reference_failed: Option<String>) -> StudyReport {
        let runs_failed = self.study.runs_failed(&self.runs, self.out);
        let failure = reference_failed.map(Error::Solve).or(runs_failed);
        StudyReport {
            runs: self.runs,
            summary: self.summary,
            failure,
        }
    }
}
