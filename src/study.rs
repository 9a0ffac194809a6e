//! Convergence studies: one scene run over a list of mesh refinements and variants, in one
//! process (`mortar study STUDY.toml`), measured against the mesh size; optionally, curves of the
//! runs' load histories compared between variants (force against displacement, say).
//!
//! # The study file
//!
//! Every key is documented where it is declared ([`StudyFile`], [`RefinementSpec`],
//! [`VariantSpec`], [`CurvesSpec`]); unknown keys are errors.
//!
//! ```toml
//! case = "case.toml"                 # the base scene, relative to the study file
//! metric = "energy_error"            # the summary metric measured against h
//! title = "Thick sphere"             # plot title (optional)
//!
//! [[refinement]]                     # at least 1 (2 or more for a slope)
//! h = 0.5                            # mesh size for the x axis
//! set = { "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2 }
//!
//! [[variant]]                        # at least 1
//! name = "hex20"                     # in file names and metric names: slope_<name>
//! set = { "mesh.0.element" = "hex20" }
//! ```
//!
//! A study of load curves, such as the force-displacement curves of sliding blocks (one
//! refinement, four variants; `metric` is still recorded per run in `study.csv`):
//!
//! ```toml
//! case = "case.toml"
//! metric = "slip_force_ratio"
//! title = "Sliding blocks: tangential reaction"
//!
//! [[refinement]]
//! h = 1.0
//!
//! [[variant]]
//! name = "case1"
//! [[variant]]
//! name = "case2"
//! set = { "interface.0.passes" = 1 }
//!
//! [curves]                           # compare history.csv curves of the variants
//! x = "u_upper.zmax_x"               # history.csv columns
//! y = "reaction_upper.zmax_x"
//! x_label = "prescribed displacement"  # axis labels (default: the column names)
//! y_label = "tangential force"
//! reference = "case1"                # the variant the others are compared with
//! after = 0.0                        # compare only points with x > after
//! abs = true                         # plot and compare |y|
//! ```
//!
//! # Edits
//!
//! Each run is the base case, then the variant's `set`, then the refinement's `set`, then the
//! variant's `refinement_set[level]` if it has one (a later setting of the same path wins),
//! applied to the case's TOML table before it is validated
//! ([`Scene::load_edited`]). A path is dotted: a segment that is a number indexes an array (of
//! tables: `mesh.0` is the first `[[mesh]]`), any other names a key of a table. The value
//! replaces what is there (a table value replaces a whole table). A missing key may be created in
//! a table (with tables created for the rest of the path: `"steps.count" = 4` works on a case
//! without `[steps]`); the case parser then validates it like any key. A path that cannot lead
//! anywhere is an error naming the study key and the path: an index past the end of an array or
//! into a missing key, a name used on an array, a path through a number or a string. Write
//! dotted paths in quotes: TOML reads `mesh.0.n_circ = 2` unquoted as nested tables, which this
//! refuses with a hint.
//!
//! Before any run, every variant x refinement is built and validated (paths, case keys, mesh),
//! so a mistake in the last variant is reported at once, not after the first runs. Every run
//! shares one PETSc: its options are the base case's options file (no variant may change
//! `petsc_options`), the command line, and the variant's own `petsc` options, set for its runs
//! only (options a variant sets that none of its runs reads draw one warning naming the
//! variant, after its last run).
//! A variant with `ranks = k` runs on the first k ranks of the job (a split communicator); the
//! other ranks wait for it (OpenMPI's waiting polls, so on a machine with as many cores as
//! ranks the waiting rank takes a little of the time measured).
//!
//! The first run of a process pays one-time costs (loading the solver libraries, first
//! allocations): an untimed run of the first variant at the first level comes first, into
//! `<out>/warm_up/`, unless that variant is the `[curves]` reference (not on the front).
//!
//! # Errors against the finest run
//!
//! A metric that is a value, not an error (a peak pressure, a tip displacement: nothing exact
//! to compare with), becomes one with `finest_reference = "<variant>"`: once every run is done,
//! each converged run's error is `|m - m_ref| / |m_ref|`, the relative difference of its metric
//! to that of the named variant's run at the finest refinement (the smallest h). That run is
//! the truth: it has no error, so it is on neither plot nor the front. When it failed, or its
//! metric is 0, no run has an error and the study fails after writing its outputs. The metrics
//! as the runs reported them stay in the summary (`value_<variant>_<level>`). One metric only
//! (the largest of several values is no value). Mind what a finest run can tell: every error
//! levels off at the truth's own error, and the reference variant's slope (`slope_<variant>`,
//! over its coarser levels) comes out steeper than its true order, most at the level next to
//! the finest.
//!
//! # Curves
//!
//! With `[curves]`, the runs at the **last** refinement level are compared: each variant's
//! `history.csv` (one row per converged load step) gives the points `(x, y)` of its curve
//! (`(x, |y|)` with `abs`), in load order. For every variant other than the reference, the
//! metric `curve_max_rel_diff_<variant>` (or `<curves.metric>_<variant>`) is the largest, over the reference's points with
//! `x > after`, of `|y_v(x) - y_ref(x)| / |y_ref(x)|`, where `y_v` is the variant's curve
//! linearly interpolated at the reference's `x` (its points sorted by x; of several points at
//! one x, the last in load order). Reference points outside the variant's x range, and those
//! with `y_ref = 0`, are skipped; when none is left there is no metric. A run that failed or
//! diverged is still plotted with the points it has (its converged steps) and compared over the
//! overlap; one that failed before its first step has no points. Steps accepted without
//! convergence (`steps.on_failure = "continue"`: `converged` = 0 in the history) are ringed
//! on the plot, and the legend gives their number and, for a run that stopped early, the x
//! where it stopped. Every variant also gets `smoothness_<variant>`: the largest change of y
//! between consecutive points with `x > after` over the mean change (about 1-2 for a smooth
//! curve of even steps; a spike k times the typical step gives about k). The column names are
//! checked against the first run's `history.csv`, so a misspelt one stops the study after one
//! run.
//!
//! # Outputs (in `--out DIR`, default `out/<study name>`; written by rank 0)
//!
//! - `runs/<variant>/<level>/`: each run's own outputs (`level` = index of the refinement),
//!   emptied before the run, so that nothing an earlier study left there passes for its own.
//!   A study stopped by SIGINT or SIGTERM ([`crate::interrupt`]) ends once the run it was in
//!   stops (at its next Newton iteration; a run on fewer ranks than the job, or one of its
//!   `repeat`s, may finish first), with the runs that finished in `study.csv`.
//! - `study.csv`: one row per run, rewritten after every run: `variant, level, h, ranks,
//!   error` (the metric, or the largest of the metrics; with `finest_reference` the relative
//!   difference to the finest run's, rewritten once every run is done; empty for a failed
//!   run), `seconds` (wall clock; with `repeat`, the fastest of the run's converged repeats),
//!   `seconds_slowest` (the slowest of them), `newton_its` (total over the steps that
//!   converged), `converged` (`true`/`false`), `augmentations` (Uzawa, over the steps),
//!   `peak_memory_mb` (peak resident memory of the run, largest over the ranks: Linux's
//!   `VmHWM`, reset before each run; the runs share one process, so before each run the
//!   memory the earlier ones freed goes back to the OS, [`Petsc::release_free_memory`], or a
//!   run after a larger one would report that one's peak), `on_front` (see below).
//! - `summary.json` ([`Summary`]): `case` = the study name (the study file's folder and stem,
//!   `contact_patch_study` for `cases/contact_patch/study.toml`: the studies of one scene, and
//!   the `study.toml` of every scene, get folders of their own), `converged` =
//!   every run converged, `metrics`: `slope_<variant>` (least-squares slope of log(error)
//!   against log(h) over the variant's converged runs, when there are two or more) and
//!   `error_<variant>_<level>`; for every converged run, each metric of its own
//!   `summary.json` as `<metric>_<variant>_<level>` (`max_newton_its_case1_0`,
//!   `max_augmentations_per_step_case1_0`, `rel_error_peak_pressure_hex20_2`, ...), its wall
//!   time `seconds_<variant>_<level>` and its peak memory `peak_memory_mb_<variant>_<level>`,
//!   so that expectations can bound them (`max_newton_its_* <= 8`); plus `failed_runs`, with
//!   `finest_reference` the values
//!   `value_<variant>_<level>`, and with `[curves]`
//!   `curve_max_rel_diff_<variant>` and `smoothness_<variant>` (see above, added once every
//!   run is done); `timings.total`;
//!   `message` lists the failed runs. Rewritten after every run.
//! - `convergence.png`, `convergence.svg`: the log-log plot of error against h, one line per
//!   variant, the slopes in the legend ([`crate::io::plot::loglog`]); only with 2 or more
//!   refinements.
//! - With `[curves]`: `curves.png`, `curves.svg`: y against x on linear axes, one line per
//!   variant (its run at the last level), `title` as the title ([`crate::io::plot::lines`]).
//! - `pareto.png`, `pareto.svg`: the error against wall time on log-log axes, every converged
//!   run a point, its **Pareto front** ringed: the runs that no other run beats in both (no
//!   more time and no larger error, one of them strictly; errors at or below the study's
//!   `error_floor` count as equal, and so do errors within its `error_noise` of each other
//!   (relative: far below any discretization error) and wall times within its `time_noise`;
//!   [`pareto_front`]);
//!   variants with `reference_only = true`
//!   are plotted but not candidates. Without `[curves]` the error is the metric (with
//!   `finest_reference`, its relative difference to the finest run's); with `[curves]` (no
//!   exact solution: the reference variant is the truth) it is a variant's
//!   `curve_max_rel_diff` at the last level, and the reference is not on the plot.
//!   The summary gets `on_front_<variant>_<level>` (1 or 0) and, for the default variant (the
//!   first with no edits, no `refinement_set`, no `petsc`, no `ranks` and not
//!   `reference_only`: the case file as it is), `default_on_front`, the share of its runs on
//!   the front (its failed runs counted, off it; not its `finest_reference` run, the truth);
//!   the closing line says it.
//!   `study.csv`'s `on_front` column has the flags.
//!
//! A failed run (not converged, steps accepted unconverged under `steps.on_failure =
//! "continue"`, a bad value of a PETSc option, a solver package PETSc lacks: found when the run
//! sets up its solver, `ksp::probe_factorization`, ...) is recorded (`converged = false`, no
//! point on the convergence plot) and the study goes
//! on; when any failed, the study fails after writing everything and printing its
//! expectations (checked on what the other runs measured: [`StudyReport::failure`]), unless every
//! failed run belongs to a variant with `may_fail = true` (a baseline expected to break). A
//! metric missing from a converged run's summary stops the study: it would be missing from
//! every run. So does an error that need not reach every rank alike (an error PETSc raises
//! inside a solve; I/O), and a file a run cannot write (`Error::Output`, which the next runs
//! would meet too): the message names the variant and level, also when one rank of a
//! 2-rank run meets it and aborts the job (`error::with_context`). A run's folder
//! `runs/<variant>/<level>/` is emptied before it runs, so that nothing of an earlier study in
//! the same `--out` passes for this run's.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use mpi::collective::{CommunicatorCollectives, Root, SystemOperation};
use mpi::topology::Communicator;
use serde::Deserialize;

use crate::case::Scene;
use crate::error::{print_warning, Error, Result};
use crate::io::case_file::one_line;
use crate::io::output::{lock_folder, read_csv, write_atomic, Summary};
use crate::io::plot;
use crate::petsc::Petsc;
use crate::solver::{self, RunOptions};

/// The study file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// The base scene: a case file, relative to the study file.
    pub case: String,
    /// The metric of the runs' `summary.json` measured against h (`energy_error` for the Lamé
    /// sphere), or a list of metrics whose largest absolute value is the run's error (a patch
    /// test measures both the stress and the penetration: `["max_rel_stress_error",
    /// "max_rel_penetration_blocks"]`, named `max(max_rel_stress_error, ...)` in the outputs).
    pub metric: MetricSpec,
    /// Plot title (of both plots). Default: `<scene name>: <metric>` for the convergence plot,
    /// `<scene name>: <y label>` for the curves.
    pub title: Option<String>,
    /// Mesh refinements, at least 1, each with its mesh size: 2 or more give each variant a
    /// convergence slope and the convergence plot; 1 is a sweep of the variants on one mesh
    /// (the Pareto front and the expectations work alike).
    #[serde(default)]
    pub refinement: Vec<RefinementSpec>,
    /// Variants (element types, schemes, ...), at least 1: each is run at every refinement.
    #[serde(default)]
    pub variant: Vec<VariantSpec>,
    /// Curves of the runs' load histories to plot and compare between variants (see the module
    /// docs). Default: none.
    pub curves: Option<CurvesSpec>,
    /// Errors at or below this value count as equal on the Pareto front (round-off: a patch
    /// test's runs are all exact, and the fastest of them is the one to pick). Finite, >= 0.
    /// Default 0.
    #[serde(default)]
    pub error_floor: f64,
    /// Errors within this fraction of each other (of the larger) count as equal on the Pareto
    /// front: differences far below any discretization error, such as the same integrals
    /// summed in another order, or two quadratures that are exact to 12 digits (the two pallet
    /// splits on the Hertz scene's curved faces), where the slower run would otherwise stay on
    /// the front by an error smaller in the last digits. Finite, in [0, 1). Default 1e-9.
    #[serde(default = "default_error_noise")]
    pub error_noise: f64,
    /// How many times each run is made: its wall time is the fastest of them (noise from other
    /// work on the machine only ever adds time), its other results those of the first, whose
    /// outputs stay in `runs/` (the repeats write to `runs/<variant>/<level>.repeat/`, removed
    /// afterwards). A repeat counts only when it converges in as many Newton iterations as the
    /// first (on more than one rank round-off of the parallel solve may take another path).
    /// `study.csv` gives the slowest time too. Reference variants (`reference_only`, the
    /// `[curves]` reference), whose times are not compared, run once. From 1 to 10. Default 1.
    #[serde(default = "default_repeat")]
    pub repeat: usize,
    /// Wall times within this fraction of each other count as equal on the Pareto front: the
    /// machine's noise (two runs that do the same work differ by a few per cent, and the
    /// faster of them would otherwise push the other off the front). Finite, in [0, 1).
    /// Default 0.
    #[serde(default)]
    pub time_noise: f64,
    /// Checks on the study's summary metrics (`slope_* >= 1.9`; see `crate::expect`): printed
    /// with their measured values after the study, which fails when one does not hold.
    /// Default: none.
    #[serde(default)]
    pub expect: Vec<String>,
    /// For a metric that is a value, not an error (a peak pressure, a tip displacement, with no
    /// exact value to compare with): the variant whose run at the finest refinement (the
    /// smallest h) is the truth. Every other run's error is then `|m - m_ref| / |m_ref|`, its
    /// metric's relative difference to that run's; the reference run itself has no error (not
    /// on the plots or the front). One metric, not a list. Not with `[curves]`, whose
    /// `reference` plays this part. Default: none (the metric is an error).
    pub finest_reference: Option<String>,
}

/// The most runs `repeat` may ask for each variant and level.
const MAX_REPEAT: usize = 10;

/// `repeat` when the study file does not set it.
fn default_repeat() -> usize {
    1
}

/// `error_noise` when the study file does not set it: errors that agree to nine digits are the
/// same error for every metric a study measures.
fn default_error_noise() -> f64 {
    1e-9
}

/// The study's `metric`: one name, or several whose largest absolute value is the error.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged, expecting = "a metric name or a list of metric names")]
pub enum MetricSpec {
    One(String),
    Largest(Vec<String>),
}

impl MetricSpec {
    /// The metric names.
    fn names(&self) -> Vec<String> {
        match self {
            MetricSpec::One(m) => vec![m.clone()],
            MetricSpec::Largest(ms) => ms.clone(),
        }
    }
}

/// The `[curves]` table: one curve per variant, from the `history.csv` of its run at the last
/// refinement level, plotted in `curves.png`/`curves.svg` and compared with the reference
/// variant's (`curve_max_rel_diff_<variant>` in the study summary; see the module docs). A run
/// that failed or diverged is plotted with the points it has (its converged steps) and compared
/// over the overlap.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurvesSpec {
    /// The `history.csv` column of the x axis, e.g. `u_upper.zmax_x` (the mean displacement of
    /// a constrained set along x). A column the runs do not write is an error listing those they
    /// do.
    pub x: String,
    /// The `history.csv` column of the y axis, e.g. `reaction_upper.zmax_z` (the reaction force
    /// on a constrained set along z).
    pub y: String,
    /// The x axis label. Default: the column name `x`.
    pub x_label: Option<String>,
    /// The y axis label. Default: the column name `y` (as `|y|` with `abs`).
    pub y_label: Option<String>,
    /// The name of the variant the others are compared with (must be one of the variants).
    pub reference: String,
    /// Compare only the points with x > `after` (e.g. 0 to leave out a first phase in which x
    /// stays 0); the plot shows every point. Default: -infinity (every point).
    pub after: Option<f64>,
    /// Plot and compare |y| instead of y (a compressive reaction is negative). Default: false.
    #[serde(default)]
    pub abs: bool,
    /// The name of the comparison metrics, `<metric>_<variant>` in the study summary (e.g.
    /// `tip_rel_diff` for a beam's tip). Letters, digits and `_`. Default: `curve_max_rel_diff`.
    pub metric: Option<String>,
}

/// One mesh refinement.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefinementSpec {
    /// Mesh size (the plot's x axis and the slope's h), finite and > 0, different for every
    /// refinement.
    pub h: f64,
    /// Edits of the case: dotted path = value (see the module docs). Applied after the
    /// variant's. Default: none.
    #[serde(default)]
    pub set: toml::Table,
}

/// One variant of the scene.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantSpec {
    /// Name: letters, digits, `_` and `-`, unique; used in file names (`runs/<name>/`) and metric
    /// names (`slope_<name>`).
    pub name: String,
    /// Edits of the case: dotted path = value (see the module docs). Default: none.
    #[serde(default)]
    pub set: toml::Table,
    /// Edits per refinement level, applied last (after the refinement's own `set`): one table
    /// per refinement, for a variant whose mesh follows the level differently (e.g. a
    /// conforming mesh where the others are dissimilar). Default: none.
    #[serde(default)]
    pub refinement_set: Vec<toml::Table>,
    /// A baseline expected to break (node-on-segment in the paper's Figure 7): when its run
    /// fails, the failure is recorded, plotted and reported as for any run, but does not make
    /// the study fail. Default false.
    #[serde(default)]
    pub may_fail: bool,
    /// Shown for comparison but not a choice of the scene's settings (a conforming mesh where
    /// the scene is about dissimilar ones): its runs are plotted but never on the Pareto front.
    /// Default false.
    #[serde(default)]
    pub reference_only: bool,
    /// PETSc options of this variant's runs, written as on the command line
    /// (`"-ksp_type gmres -pc_type gamg"`): put into PETSc's options database for its runs
    /// only, over the options file and the command line, and restored after each run.
    /// Default: none.
    pub petsc: Option<String>,
    /// Runs this variant on the first `ranks` ranks of the study's job only (from 1 to the
    /// number of ranks the study runs on; the other ranks wait), so that one study measures
    /// the speedup: `mpirun -n 2 mortar study` with variants `ranks = 1` and `ranks = 2`.
    /// Default: every rank of the job.
    pub ranks: Option<usize>,
}

impl VariantSpec {
    /// The scene's own settings: no edits, no PETSc options, every rank, a choice (not
    /// `reference_only`). The study's first such variant is its defaults (`default_on_front`).
    pub fn is_default(&self) -> bool {
        self.set.is_empty()
            && self.refinement_set.is_empty()
            && self.petsc.is_none()
            && self.ranks.is_none()
            && !self.reference_only
    }
}

/// A validated study.
#[derive(Clone, Debug)]
pub struct Study {
    /// Study name, `<folder>_<stem>` of the study file (`hertz_study` for
    /// `cases/hertz/study.toml`): `case` in its summary, the default output folder.
    pub name: String,
    /// The study file.
    pub file: PathBuf,
    /// The base case file.
    pub case: PathBuf,
    /// The error's name in the outputs: the metric, or `max(a, b, ...)`.
    pub metric: String,
    /// The summary metrics whose largest absolute value is a run's error.
    pub metric_parts: Vec<String>,
    pub title: String,
    pub refinements: Vec<RefinementSpec>,
    pub variants: Vec<VariantSpec>,
    /// Each variant's own PETSc options (`VariantSpec::petsc`), parsed: names and values.
    pub variant_options: Vec<Vec<(String, Option<String>)>>,
    /// The PETSc options file of the base case (shared by every run).
    pub petsc_options: Option<PathBuf>,
    /// The `[curves]` table, validated.
    pub curves: Option<Curves>,
    /// Errors at or below this count as equal on the Pareto front (`error_floor`).
    pub error_floor: f64,
    /// Relative error differences at or below this count as equal (`error_noise`).
    pub error_noise: f64,
    /// Runs per variant and level, the fastest timed (`repeat`).
    pub repeat: usize,
    /// Relative wall-time differences at or below this count as equal (`time_noise`).
    pub time_noise: f64,
    /// Checks on the study's metrics (`expect`).
    pub expectations: Vec<crate::expect::Expectation>,
    /// The variant whose finest run is the truth (`finest_reference`), validated.
    pub finest_reference: Option<String>,
}

/// A validated `[curves]` table ([`CurvesSpec`]), defaults resolved.
#[derive(Clone, Debug)]
pub struct Curves {
    /// The history column of the x axis.
    pub x: String,
    /// The history column of the y axis.
    pub y: String,
    pub x_label: String,
    pub y_label: String,
    /// The reference variant's name.
    pub reference: String,
    /// Points with x <= `after` are not compared.
    pub after: f64,
    /// Plot and compare |y|.
    pub abs: bool,
    /// The curves plot's title.
    pub title: String,
    /// The comparison metrics are `<metric>_<variant>`.
    pub metric: String,
}

/// One run of a study, as recorded in `study.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    pub variant: String,
    pub level: usize,
    pub h: f64,
    /// The ranks the run ran on.
    pub ranks: usize,
    /// The metric, for a converged run.
    pub error: Option<f64>,
    /// Wall clock: the fastest of the run's converged repeats (`repeat`).
    pub seconds: f64,
    /// The slowest of them (`seconds` itself without repeats).
    pub seconds_slowest: f64,
    pub newton_its: usize,
    /// Uzawa augmentations over the run's steps.
    pub augmentations: usize,
    /// Peak resident memory of the run (largest over the ranks), MB; `None` where Linux's
    /// `/proc/self` is not there.
    pub peak_memory_mb: Option<f64>,
    pub converged: bool,
    /// On the Pareto front of error against wall time (see [`pareto_front`]).
    pub on_front: bool,
    /// Why the run failed.
    pub message: Option<String>,
    /// The metrics of the run's own `summary.json`, for a converged run, on the ranks that ran
    /// it (read on rank 0 only, where the study summary is made).
    pub metrics: BTreeMap<String, f64>,
}

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
    /// Reads a study file and validates it, with every variant x refinement of its case
    /// (paths, keys, mesh). Errors name the study file and the key.
    pub fn load(path: &Path) -> Result<Study> {
        let err = |msg: String| Error::Case {
            file: path.to_path_buf(),
            msg,
        };
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let file: StudyFile = toml::from_str(&text).map_err(|e| err(one_line(&e.to_string())))?;
        let name = study_name(path);
        let metric_parts = file.metric.names();
        if metric_parts.is_empty() || metric_parts.iter().any(|m| m.trim().is_empty()) {
            return Err(err("metric: empty".into()));
        }
        if !(file.error_floor.is_finite() && file.error_floor >= 0.0) {
            return Err(err(format!(
                "error_floor = {}: must be finite and >= 0",
                file.error_floor
            )));
        }
        if !(1..=MAX_REPEAT).contains(&file.repeat) {
            return Err(err(format!(
                "repeat = {}: must be from 1 to {MAX_REPEAT}",
                file.repeat
            )));
        }
        if !(file.error_noise.is_finite() && (0.0..1.0).contains(&file.error_noise)) {
            return Err(err(format!(
                "error_noise = {}: must be finite, >= 0 and < 1",
                file.error_noise
            )));
        }
        if !(file.time_noise.is_finite() && (0.0..1.0).contains(&file.time_noise)) {
            return Err(err(format!(
                "time_noise = {}: must be finite, >= 0 and < 1",
                file.time_noise
            )));
        }
        if file.refinement.is_empty() {
            return Err(err("refinement: at least 1 is needed, found none".into()));
        }
        for (i, r) in file.refinement.iter().enumerate() {
            if !(r.h.is_finite() && r.h > 0.0) {
                return Err(err(format!(
                    "refinement[{i}].h = {}: must be finite and > 0",
                    r.h
                )));
            }
            if let Some(j) = file.refinement[..i].iter().position(|o| o.h == r.h) {
                return Err(err(format!(
                    "refinement[{i}].h = {} repeats refinement[{j}].h",
                    r.h
                )));
            }
        }
        if file.variant.is_empty() {
            return Err(err("variant: at least 1 is needed, found none".into()));
        }
        let mut names = BTreeSet::new();
        for (i, v) in file.variant.iter().enumerate() {
            let ok = !v.name.is_empty()
                && v.name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !ok {
                return Err(err(format!(
                    "variant[{i}].name = \"{}\": use letters, digits, '_' and '-' (it names \
                     folders and metrics)",
                    v.name
                )));
            }
            if v.ranks == Some(0) {
                return Err(err(format!("variant[{i}].ranks = 0: at least 1")));
            }
            if !names.insert(v.name.as_str()) {
                return Err(err(format!(
                    "variant[{i}].name = \"{}\" is used twice",
                    v.name
                )));
            }
        }
        if let Some(r) = &file.finest_reference {
            if metric_parts.len() > 1 {
                return Err(err(format!(
                    "finest_reference = \"{r}\": needs one metric, not a list (the largest of \
                     several values is no value to compare)"
                )));
            }
            if file.curves.is_some() {
                return Err(err(format!(
                    "finest_reference = \"{r}\": not with [curves] (curves.reference is the \
                     truth there)"
                )));
            }
            if !names.contains(r.as_str()) {
                return Err(err(format!(
                    "finest_reference = \"{r}\": no such variant (variants: {})",
                    file.variant
                        .iter()
                        .map(|v| v.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        if let Some(c) = &file.curves {
            for (key, column) in [("x", &c.x), ("y", &c.y)] {
                if column.trim().is_empty() {
                    return Err(err(format!("curves.{key}: empty (a history.csv column)")));
                }
            }
            if !names.contains(c.reference.as_str()) {
                return Err(err(format!(
                    "curves.reference = \"{}\": no such variant (variants: {})",
                    c.reference,
                    file.variant
                        .iter()
                        .map(|v| v.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            if let Some(m) = &c.metric {
                let ok =
                    !m.is_empty() && m.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_');
                if !ok {
                    return Err(err(format!(
                        "curves.metric = \"{m}\": letters, digits and _ only"
                    )));
                }
            }
            if c.after.is_some_and(f64::is_nan) {
                return Err(err("curves.after: not a number".into()));
            }
        }
        let dir = path.parent().unwrap_or(Path::new(""));
        let case = dir.join(&file.case);
        if !case.is_file() {
            return Err(err(format!(
                "case = \"{}\": no such file {}",
                file.case,
                case.display()
            )));
        }

        // The paths, against the case as written: errors name the study key.
        let case_text = std::fs::read_to_string(&case).map_err(|e| Error::io(&case, e))?;
        let base: toml::Table = toml::from_str(&case_text).map_err(|e| Error::Case {
            file: case.clone(),
            msg: one_line(&e.to_string()),
        })?;
        for (i, v) in file.variant.iter().enumerate() {
            if !v.refinement_set.is_empty() && v.refinement_set.len() != file.refinement.len() {
                return Err(err(format!(
                    "variant[{i}].refinement_set has {} tables for {} refinements",
                    v.refinement_set.len(),
                    file.refinement.len()
                )));
            }
            for (j, r) in file.refinement.iter().enumerate() {
                let mut t = base.clone();
                apply_sets(&mut t, &edits(i, v, j, r)).map_err(err)?;
            }
        }

        let variant_options = file
            .variant
            .iter()
            .enumerate()
            .map(|(i, v)| {
                crate::petsc::options::parse(v.petsc.as_deref().unwrap_or("")).map_err(|m| {
                    err(format!(
                        "variant[{i}].petsc = \"{}\": {m}",
                        v.petsc.as_deref().unwrap_or("")
                    ))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let mut study = Study {
            name,
            variant_options,
            file: path.to_path_buf(),
            case,
            metric: match metric_parts.as_slice() {
                [one] => one.clone(),
                many => format!("max({})", many.join(", ")),
            },
            metric_parts,
            title: String::new(),
            refinements: file.refinement,
            variants: file.variant,
            petsc_options: None,
            curves: None,
            error_floor: file.error_floor,
            error_noise: file.error_noise,
            repeat: file.repeat,
            time_noise: file.time_noise,
            expectations: crate::expect::parse_all("expect", &file.expect).map_err(err)?,
            finest_reference: file.finest_reference,
        };
        // Every run's scene, built and dropped one at a time.
        let base_scene = Scene::load(&study.case)?;
        study.petsc_options = base_scene.petsc_options.clone();
        study.curves = file.curves.map(|c| {
            let y_label = c.y_label.unwrap_or_else(|| {
                if c.abs {
                    format!("|{}|", c.y)
                } else {
                    c.y.clone()
                }
            });
            Curves {
                x_label: c.x_label.unwrap_or_else(|| c.x.clone()),
                title: file
                    .title
                    .clone()
                    .unwrap_or_else(|| format!("{}: {y_label}", base_scene.name)),
                y_label,
                x: c.x,
                y: c.y,
                reference: c.reference,
                after: c.after.unwrap_or(f64::NEG_INFINITY),
                abs: c.abs,
                metric: c.metric.unwrap_or_else(|| "curve_max_rel_diff".to_string()),
            }
        });
        study.title = file
            .title
            .unwrap_or_else(|| format!("{}: {}", base_scene.name, study.metric));
        drop(base_scene);
        for i in 0..study.variants.len() {
            for j in 0..study.refinements.len() {
                let scene = study.scene(i, j)?;
                if scene.petsc_options != study.petsc_options {
                    return Err(err(format!(
                        "variant '{}' at refinement[{j}] changes petsc_options: every run of a \
                         study shares one PETSc (give options on the command line or in the \
                         variant's petsc key instead)",
                        study.variants[i].name
                    )));
                }
            }
        }
        Ok(study)
    }

    /// The scene of variant `v` at refinement `level`; errors name the study, the variant and
    /// the refinement.
    pub fn scene(&self, v: usize, level: usize) -> Result<Scene> {
        let (variant, refinement) = (&self.variants[v], &self.refinements[level]);
        let sets = edits(v, variant, level, refinement);
        Scene::load_edited(&self.case, |t| apply_sets(t, &sets)).map_err(|e| Error::Case {
            file: self.file.clone(),
            msg: format!("variant '{}' at refinement[{level}]: {e}", variant.name),
        })
    }

    /// Runs every variant at every refinement (variant by variant, coarsest refinement as
    /// listed first) and writes the study's outputs in `opts.out_dir` (see the module docs).
    /// Progress (one line per run) on rank 0 unless `opts.quiet`. Runs that failed (and were
    /// not allowed to), or a `finest_reference` run that failed, do not make this an error:
    /// everything is written, and the report's [`StudyReport::failure`] holds the study's
    /// error, for the caller to return once it has checked the expectations. An error here is
    /// one that stopped the study (a bad path, an I/O error, a missing metric, ...).
    pub fn run(&self, petsc: &Petsc, opts: &RunOptions) -> Result<StudyReport> {
        let rank = petsc.rank();
        let say = |msg: String| {
            if rank == 0 && !opts.quiet {
                println!("{msg}");
            }
        };
        let out = &opts.out_dir;
        let job_size = petsc.size();
        // (Before the output folder is made: a refused study leaves nothing behind.)
        if let Some((i, v)) = self
            .variants
            .iter()
            .enumerate()
            .find(|(_, v)| v.ranks.is_some_and(|r| r > job_size))
        {
            return Err(Error::Case {
                file: self.file.clone(),
                msg: format!(
                    "variant[{i}].ranks = {}: the study runs on {job_size} rank(s) (mpirun -n {} \
                     mortar study ...)",
                    v.ranks.unwrap_or(0),
                    v.ranks.unwrap_or(0)
                ),
            });
        }
        // The folder's lock (rank 0), held to the study's end: a second study (or run) into
        // it would empty the run folders of this one.
        let locked = if rank == 0 {
            lock_folder(out)
        } else {
            Ok(None)
        };
        let (agreed, _lock) = match locked {
            Ok(lock) => (Ok(()), lock),
            Err(e) => (Err(e), None),
        };
        crate::solver::agree_on(&petsc.world(), agreed)?;
        let started = Instant::now();
        let total = self.variants.len() * self.refinements.len();
        say(format!(
            "mortar study {}: {} variant(s) x {} refinement(s) = {total} runs of {} on {} \
             rank(s) -> {}",
            self.name,
            self.variants.len(),
            self.refinements.len(),
            self.case.display(),
            petsc.size(),
            out.display()
        ));
        let first_is_reference = self
            .curves
            .as_ref()
            .is_some_and(|c| c.reference == self.variants[0].name);
        if !first_is_reference {
            // The first run of a process pays one-time costs (loading the solver libraries,
            // first allocations) that would tilt the comparison of wall times against the
            // first variant: an untimed run of the first variant's first level comes first
            // (not when that variant is the curves' reference, which is not on the front).
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
        }
        let mut runs: Vec<RunRecord> = Vec::with_capacity(total);
        let mut summary = Summary::default();
        // The curves' columns, checked against the first history written.
        let mut columns_checked = self.curves.is_none();
        for (v, variant) in self.variants.iter().enumerate() {
            // The variant's options that none of its runs read.
            let mut unread: Option<BTreeSet<String>> = None;
            for (level, refinement) in self.refinements.iter().enumerate() {
                let run_dir = out.join("runs").join(&variant.name).join(level.to_string());
                // A reused output folder: nothing of an earlier study's run may pass for this
                // run's (its summary, read when this run fails, or its history and VTU files).
                if rank == 0 && run_dir.exists() {
                    std::fs::remove_dir_all(&run_dir).map_err(|e| Error::io(&run_dir, e))?;
                }
                petsc.world().barrier();
                petsc.release_free_memory();
                reset_peak_memory();
                let ranks = variant.ranks.unwrap_or(job_size);
                let t0 = Instant::now();
                let (result, unused) = self.run_one(petsc, v, level, &run_dir)?;
                let run_interrupted = matches!(result, Some(Err(Error::Interrupted(_))));
                unread = Some(match unread {
                    None => unused,
                    Some(before) => before.intersection(&unused).cloned().collect(),
                });
                let mut missing_metric = None;
                let seconds = t0.elapsed().as_secs_f64();
                // Every rank takes part (-1: not available there).
                let local = peak_memory_mb().unwrap_or(-1.0);
                let mut most = 0.0f64;
                petsc
                    .world()
                    .all_reduce_into(&local, &mut most, SystemOperation::max());
                let peak_memory_mb = (most >= 0.0).then_some(most);
                let mut record = RunRecord {
                    variant: variant.name.clone(),
                    level,
                    h: refinement.h,
                    ranks,
                    error: None,
                    seconds,
                    seconds_slowest: seconds,
                    newton_its: 0,
                    augmentations: 0,
                    peak_memory_mb,
                    converged: false,
                    on_front: false,
                    message: None,
                    metrics: BTreeMap::new(),
                };
                match result {
                    None => {}
                    Some(Ok(s)) if !s.converged => {
                        record.newton_its = s.steps.iter().map(|st| st.newton_its).sum();
                        record.message = s.message.clone().or_else(|| {
                            let n = s.steps.iter().filter(|st| !st.converged).count();
                            Some(format!(
                                "{n} step(s) accepted without convergence \
                                 (steps.on_failure = \"continue\")"
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
                            Ok(e) => {
                                record.message = Some(format!("{} = {e}", self.metric));
                            }
                            Err(msg) => missing_metric = Some(msg),
                        }
                    }
                    // Errors every rank meets alike are this run's failure; any other (an I/O
                    // error on one rank) and a file the run could not write end the study, as
                    // they end a run.
                    Some(Err(e)) if !ends_study(&e) => {
                        if rank == 0 {
                            record.newton_its = Summary::read(&run_dir.join("summary.json"))
                                .map(|s| s.steps.iter().map(|st| st.newton_its).sum())
                                .unwrap_or(0);
                        }
                        record.message = Some(e.to_string());
                    }
                    Some(Err(e)) => return Err(self.run_error(v, level, e)),
                }
                // After the broadcast, so that ranks that waited (`ranks`) stop with the others.
                if share_record(petsc, &mut record, missing_metric.is_some()) {
                    return Err(Error::Case {
                        file: self.file.clone(),
                        msg: missing_metric.unwrap_or_default(),
                    });
                }
                if record.converged && self.repeat > 1 && !self.is_reference(variant) {
                    for t in self.repeat_times(petsc, v, level, &run_dir, record.newton_its)? {
                        record.seconds = record.seconds.min(t);
                        record.seconds_slowest = record.seconds_slowest.max(t);
                    }
                }
                // Collective over the whole job: ranks that waited out a run on fewer ranks
                // stop with the others. A run the signal stopped is left out; one that
                // finished is recorded.
                let stop = crate::interrupt::agreed(&petsc.world());
                // Rank 0's verdict (the ranks a smaller run left out have none).
                let mut run_interrupted = i32::from(run_interrupted);
                petsc
                    .world()
                    .process_at_rank(0)
                    .broadcast_into(&mut run_interrupted);
                if stop.is_none() || run_interrupted == 0 {
                    say(progress_line(&self.metric, &record));
                    runs.push(record);
                    if rank == 0 {
                        write_atomic(&out.join("study.csv"), study_csv(&runs).as_bytes())?;
                        summary =
                            self.summary(&runs, petsc.size(), started.elapsed().as_secs_f64());
                        summary.write(&out.join("summary.json"))?;
                    }
                }
                if let Some(signal) = stop {
                    return Err(self.interrupted(signal, &self.run_label(v, level), &runs, out));
                }
                if !columns_checked {
                    columns_checked = self.check_columns(petsc, &run_dir)?;
                }
            }
            let unread = unread.unwrap_or_default();
            if rank == 0 && !unread.is_empty() {
                print_warning(format_args!(
                    "variant '{}': PETSc option(s) {} not used by any of its \
                     runs (a typo, or an option of a solver not in use)",
                    variant.name,
                    unread.into_iter().collect::<Vec<_>>().join(", ")
                ));
            }
        }
        // With `finest_reference`, the metrics become errors against the finest run's.
        let mut reference_failed = None;
        if let Some(reference) = &self.finest_reference {
            let finest = self.finest_level();
            let (values, truth) = errors_against_finest(&mut runs, reference, finest);
            if truth.is_none() {
                reference_failed = Some(format!(
                    "study {}: the finest_reference run ({reference} at level {finest}) failed \
                     or its {} is 0 or not finite: no run has an error",
                    self.name, self.metric
                ));
            }
            if rank == 0 {
                summary = self.summary(&runs, petsc.size(), started.elapsed().as_secs_f64());
                for (r, value) in runs.iter().zip(&values) {
                    if let Some(value) = value {
                        summary
                            .metrics
                            .insert(format!("value_{}_{}", r.variant, r.level), *value);
                    }
                }
                if reference_failed.is_some() {
                    summary.message.clone_from(&reference_failed);
                }
                // Written with the Pareto front below.
            }
        }
        if self.curves.is_none() {
            for i in self.front(&runs) {
                runs[i].on_front = true;
            }
        }
        let failed = runs.iter().filter(|r| !r.converged).count();
        if rank == 0 {
            let mut done = Vec::new();
            if self.refinements.len() >= 2 {
                let series: Vec<plot::Series> = self
                    .variants
                    .iter()
                    .map(|v| plot::Series {
                        name: v.name.clone(),
                        points: points_of(&runs, &v.name),
                        ..Default::default()
                    })
                    .collect();
                let warnings = plot::loglog(
                    &out.join("convergence"),
                    &self.title,
                    "mesh size h",
                    &self.error_label(),
                    &series,
                )?;
                plot::print_warnings(warnings);
                let slopes: Vec<String> = self
                    .variants
                    .iter()
                    .map(|v| {
                        let s = plot::fitted_slope(&points_of(&runs, &v.name));
                        if s.is_finite() {
                            format!("{} {s:.3}", v.name)
                        } else {
                            format!("{} (none)", v.name)
                        }
                    })
                    .collect();
                done.push(format!("slopes {}", slopes.join(", ")));
            }
            if self.curves.is_none() {
                done.push(self.write_pareto(&runs, &self.error_label(), &mut summary, out)?);
                write_atomic(&out.join("study.csv"), study_csv(&runs).as_bytes())?;
            }
            if let Some(curves) = &self.curves {
                let figures = self.write_curves(curves, out)?;
                // The Pareto front of the curves' difference to the reference against time.
                let mut scored = curve_scores(&runs, curves, &figures, self.refinements.len() - 1);
                for i in self.front(&scored) {
                    runs[i].on_front = true;
                    scored[i].on_front = true;
                }
                let label = format!("{} to {}", curves.metric, curves.reference);
                done.push(self.write_pareto(&scored, &label, &mut summary, out)?);
                write_atomic(&out.join("study.csv"), study_csv(&runs).as_bytes())?;
                for (name, d) in &figures.differences {
                    if let Some(d) = d {
                        summary
                            .metrics
                            .insert(format!("{}_{name}", curves.metric), *d);
                    }
                }
                for (name, s) in &figures.smoothness {
                    if let Some(s) = s {
                        summary.metrics.insert(format!("smoothness_{name}"), *s);
                    }
                }
                summary.write(&out.join("summary.json"))?;
                let diffs: Vec<String> = figures
                    .differences
                    .iter()
                    .map(|(name, d)| match d {
                        Some(d) => format!("{name} {d:.3e}"),
                        None => format!("{name} (none)"),
                    })
                    .collect();
                done.push(format!(
                    "curves: largest relative difference to {}: {}",
                    curves.reference,
                    if diffs.is_empty() {
                        "(no other variant)".to_string()
                    } else {
                        diffs.join(", ")
                    }
                ));
            }
            done.push(format!("{} of {total} runs converged", total - failed));
            say(format!(
                "mortar study {}: {} -> {}",
                self.name,
                done.join("; "),
                out.display()
            ));
        }
        let may_fail = |r: &&RunRecord| {
            self.variants
                .iter()
                .any(|v| v.name == r.variant && v.may_fail)
        };
        let unexpected = runs.iter().filter(|r| !r.converged && !may_fail(r)).count();
        let runs_failed = (unexpected > 0).then(|| {
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
                "study {}: {unexpected} of {total} runs failed (see {}){first}",
                self.name,
                out.join("study.csv").display()
            ))
        });
        // The reference's failure first: without it no run has an error.
        let failure = reference_failed.map(Error::Solve).or(runs_failed);
        Ok(StudyReport {
            runs,
            summary,
            failure,
        })
    }

    /// The level of the finest refinement (the smallest h).
    fn finest_level(&self) -> usize {
        (0..self.refinements.len())
            .min_by(|&a, &b| self.refinements[a].h.total_cmp(&self.refinements[b].h))
            .unwrap_or(0)
    }

    /// What a run's error is, for plots and notes: the metric, or with `finest_reference` its
    /// relative difference to the finest run's.
    fn error_label(&self) -> String {
        match &self.finest_reference {
            Some(reference) => format!(
                "rel. diff. of {} to {reference} at h = {:.4e}",
                self.metric,
                self.refinements[self.finest_level()].h
            ),
            None => self.metric.clone(),
        }
    }

    /// The runs on the Pareto front ([`pareto_front`] with the study's `error_floor`,
    /// `error_noise` and `time_noise`), among the runs of the variants that are choices (not
    /// `reference_only`).
    fn front(&self, runs: &[RunRecord]) -> Vec<usize> {
        let choices: Vec<RunRecord> = runs
            .iter()
            .map(|r| {
                let reference = self
                    .variants
                    .iter()
                    .any(|v| v.name == r.variant && v.reference_only);
                RunRecord {
                    converged: r.converged && !reference,
                    ..r.clone()
                }
            })
            .collect();
        let ties = Ties {
            error_floor: self.error_floor,
            error_noise: self.error_noise,
            time_noise: self.time_noise,
        };
        pareto_front(&choices, ties)
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
    fn run_one(
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
                    solver::run(
                        &scene,
                        petsc,
                        &RunOptions {
                            out_dir: run_dir.to_path_buf(),
                            quiet: true,
                        },
                    )
                })
            })
        });
        let unused = options.unused().into_iter().collect();
        Ok((result, unused))
    }

    /// A variant that is never on the Pareto front, whose time is not compared: a
    /// `reference_only` one, or the `[curves]` reference.
    fn is_reference(&self, variant: &VariantSpec) -> bool {
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
    fn repeat_times(
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
    fn interrupted(&self, signal: i32, label: &str, runs: &[RunRecord], out: &Path) -> Error {
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
    fn run_error(&self, v: usize, level: usize, e: Error) -> Error {
        Error::Other(format!("{}: {e}", self.run_label(v, level)))
    }

    /// "study F: variant 'v' at level L", for the messages of that run.
    fn run_label(&self, v: usize, level: usize) -> String {
        format!(
            "study {}: variant '{}' at level {level}",
            self.file.display(),
            self.variants[v].name
        )
    }

    /// Checks the `[curves]` columns against the `history.csv` in `run_dir` (rank 0), and
    /// shares the verdict with every rank: false if there is no history yet (the run failed
    /// before its first step), true if the columns are there; an error on every rank (naming the
    /// study file, the key and the column on rank 0) if one is missing.
    fn check_columns(&self, petsc: &Petsc, run_dir: &Path) -> Result<bool> {
        let Some(curves) = &self.curves else {
            return Ok(true);
        };
        // 0: no history yet, 1: the columns are there, 2: they are not (`message`).
        let mut verdict = 0i32;
        let mut message = String::new();
        let history = run_dir.join("history.csv");
        if petsc.rank() == 0 && history.is_file() {
            verdict = 1;
            let found = read_csv(&history)
                .map_err(|e| format!("curves: cannot read {}: {e}", history.display()))
                .and_then(|(columns, _)| curves.find_columns(&history, &columns));
            if let Err(m) = found {
                message = m;
                verdict = 2;
            }
        }
        petsc
            .world()
            .process_at_rank(0)
            .broadcast_into(&mut verdict);
        match verdict {
            0 => Ok(false),
            1 => Ok(true),
            // Every rank stops; rank 0 prints its message.
            _ => Err(Error::Case {
                file: self.file.clone(),
                msg: message,
            }),
        }
    }

    /// The Pareto front of error against wall time (the flags are set on `runs`, labelled
    /// `metric`): `pareto.png` and `.svg` (every converged run a point, one line per variant,
    /// the front ringed), the summary's `on_front_<variant>_<level>` and, for the default
    /// variant ([`VariantSpec::is_default`]), `default_on_front` (the share of its runs on the
    /// front). Returns the progress note.
    fn write_pareto(
        &self,
        runs: &[RunRecord],
        metric: &str,
        summary: &mut Summary,
        out: &Path,
    ) -> Result<String> {
        // Errors at or below the floor are plotted at the floor (they count as equal; an exact
        // 0 would not show on log axes).
        let point = |r: &RunRecord| r.error.map(|e| (r.seconds, e.abs().max(self.error_floor)));
        let series: Vec<plot::Series> = self
            .variants
            .iter()
            .map(|v| {
                let mine: Vec<&RunRecord> = runs
                    .iter()
                    .filter(|r| r.variant == v.name && r.converged)
                    .collect();
                plot::Series {
                    name: v.name.clone(),
                    points: mine.iter().filter_map(|r| point(r)).collect(),
                    flagged: mine
                        .iter()
                        .filter(|r| r.on_front)
                        .filter_map(|r| point(r))
                        .collect(),
                }
            })
            .collect();
        plot::print_warnings(plot::loglog_points(
            &out.join("pareto"),
            &format!(
                "{}: {metric} against wall time (ringed: Pareto front)",
                self.name
            ),
            "wall time (s)",
            metric,
            &series,
        )?);
        for r in runs.iter().filter(|r| r.converged && r.error.is_some()) {
            summary.metrics.insert(
                format!("on_front_{}_{}", r.variant, r.level),
                f64::from(u8::from(r.on_front)),
            );
        }
        let front = runs.iter().filter(|r| r.on_front).count();
        let mut note = format!("Pareto front of {metric} against wall time: {front} run(s)");
        let default = self
            .variants
            .iter()
            .find(|v| v.is_default())
            .filter(|d| !self.is_reference(d));
        if let Some(d) = default {
            // The candidates among the runs of the defaults, the failed ones counted (off the
            // front): with [curves] those of the last level, where curves are scored (the runs
            // below it carry no error, and `converged = false`: `curve_scores`); otherwise
            // every run but the truth (the finest_reference run).
            let finest = self.finest_level();
            let last = self.refinements.len() - 1;
            let candidate = |r: &RunRecord| match &self.curves {
                Some(_) => r.level == last,
                None => {
                    !(self.finest_reference.as_deref() == Some(r.variant.as_str())
                        && r.level == finest)
                }
            };
            let mine: Vec<&RunRecord> = runs
                .iter()
                .filter(|r| r.variant == d.name && candidate(r))
                .collect();
            if !mine.is_empty() {
                let on = mine.iter().filter(|r| r.on_front).count();
                summary
                    .metrics
                    .insert("default_on_front".into(), on as f64 / mine.len() as f64);
                let _ = write!(
                    note,
                    "; the defaults (variant '{}') have {on} of {} runs on it",
                    d.name,
                    mine.len()
                );
            }
        }
        summary.write(&out.join("summary.json"))?;
        Ok(note)
    }

    /// Reads every variant's curve at the last level, writes `curves.png` and `curves.svg`
    /// (rank 0), and returns, in variant order, the largest relative difference of every
    /// variant but the reference to the reference and every variant's smoothness figure (see
    /// the module docs).
    fn write_curves(&self, curves: &Curves, out: &Path) -> Result<CurveFigures> {
        let level = self.refinements.len() - 1;
        let mut series = Vec::with_capacity(self.variants.len());
        for v in &self.variants {
            let run_dir = out.join("runs").join(&v.name).join(level.to_string());
            let history = run_dir.join("history.csv");
            let (points, flagged) = if history.is_file() {
                let (columns, rows) = read_csv(&history)?;
                let (ix, iy) =
                    curves
                        .find_columns(&history, &columns)
                        .map_err(|msg| Error::Case {
                            file: self.file.clone(),
                            msg,
                        })?;
                let point = |r: &Vec<f64>| (r[ix], if curves.abs { r[iy].abs() } else { r[iy] });
                let converged = columns.iter().position(|c| c == "converged");
                let flagged = rows
                    .iter()
                    .filter(|r| converged.is_some_and(|c| r[c] == 0.0))
                    .map(point)
                    .collect();
                (rows.iter().map(point).collect(), flagged)
            } else {
                print_warning(format_args!(
                    "curves: variant '{}' has no {} (no converged step): no \
                     curve",
                    v.name,
                    history.display()
                ));
                (Vec::new(), Vec::new())
            };
            let stopped = Summary::read(&run_dir.join("summary.json"))
                .map(|s| !s.completed)
                .unwrap_or(true);
            series.push(plot::Series {
                name: curve_legend(&v.name, &points, &flagged, stopped),
                points,
                flagged,
            });
        }
        plot::print_warnings(plot::lines(
            &out.join("curves"),
            &curves.title,
            &curves.x_label,
            &curves.y_label,
            &series,
        )?);
        let reference = self
            .variants
            .iter()
            .zip(&series)
            .find(|(v, _)| v.name == curves.reference)
            .map(|(_, s)| s.points.clone())
            .unwrap_or_default();
        let named = || self.variants.iter().map(|v| v.name.clone()).zip(&series);
        Ok(CurveFigures {
            differences: named()
                .filter(|(name, _)| *name != curves.reference)
                .map(|(name, s)| (name, max_rel_diff(&reference, &s.points, curves.after)))
                .collect(),
            smoothness: named()
                .map(|(name, s)| (name, smoothness(&s.points, curves.after)))
                .collect(),
        })
    }

    /// The study summary of the runs so far.
    fn summary(&self, runs: &[RunRecord], ranks: usize, seconds: f64) -> Summary {
        let mut s = Summary {
            case: self.name.clone(),
            ranks,
            converged: runs.len() == self.variants.len() * self.refinements.len()
                && runs.iter().all(|r| r.converged),
            ..Default::default()
        };
        s.timings.insert("total".into(), seconds);
        for v in &self.variants {
            let slope = plot::fitted_slope(&points_of(runs, &v.name));
            if slope.is_finite() {
                s.metrics.insert(format!("slope_{}", v.name), slope);
            }
        }
        for r in runs {
            if let Some(e) = r.error.filter(|e| r.converged && e.is_finite()) {
                s.metrics
                    .insert(format!("error_{}_{}", r.variant, r.level), e);
            }
            if r.converged {
                let own = r.metrics.iter().map(|(k, v)| (k.as_str(), *v));
                let measured = [
                    ("seconds", Some(r.seconds)),
                    ("peak_memory_mb", r.peak_memory_mb),
                ];
                let measured = measured.into_iter().filter_map(|(k, v)| Some((k, v?)));
                // A name already taken (a study metric, or the same name made from another
                // metric and variant: both may hold `_`) keeps its first value.
                for (name, value) in own.chain(measured).filter(|(_, v)| v.is_finite()) {
                    s.metrics
                        .entry(format!("{name}_{}_{}", r.variant, r.level))
                        .or_insert(value);
                }
            }
        }
        let failed: Vec<String> = runs
            .iter()
            .filter(|r| !r.converged)
            .map(|r| {
                format!(
                    "{} level {}: {}",
                    r.variant,
                    r.level,
                    r.message.as_deref().unwrap_or("not converged")
                )
            })
            .collect();
        s.metrics.insert("failed_runs".into(), failed.len() as f64);
        if !failed.is_empty() {
            s.message = Some(format!("failed runs: {}", failed.join("; ")));
        }
        s
    }
}

impl Curves {
    /// The indices of the x and y columns in `columns` (read from `history`); if one is missing,
    /// a message naming the key and the column and listing the columns.
    fn find_columns(
        &self,
        history: &Path,
        columns: &[String],
    ) -> std::result::Result<(usize, usize), String> {
        let find = |key: &str, name: &str| {
            columns.iter().position(|c| c == name).ok_or_else(|| {
                format!(
                    "curves.{key} = \"{name}\": no such column in {} (its columns: {})",
                    history.display(),
                    columns.join(", ")
                )
            })
        };
        Ok((find("x", &self.x)?, find("y", &self.y)?))
    }
}

/// What `[curves]` measures: per variant, the largest relative difference to the reference
/// (not for the reference itself) and the smoothness figure.
struct CurveFigures {
    differences: Vec<(String, Option<f64>)>,
    smoothness: Vec<(String, Option<f64>)>,
}

/// The legend entry of a curve: the variant's name, with the number of ringed
/// (unconverged) steps and, for a run that stopped early, the x where it stopped.
fn curve_legend(
    name: &str,
    points: &[(f64, f64)],
    flagged: &[(f64, f64)],
    stopped: bool,
) -> String {
    let mut notes = Vec::new();
    if !flagged.is_empty() {
        notes.push(format!("{} unconverged steps (ringed)", flagged.len()));
    }
    if stopped {
        match points.last() {
            Some(&(x, _)) => notes.push(format!("stopped at {x:.3}")),
            None => notes.push("failed".to_string()),
        }
    }
    if notes.is_empty() {
        name.to_string()
    } else {
        format!("{name}: {}", notes.join(", "))
    }
}

/// Smoothness of a curve: the largest change of `y` between consecutive points (load order)
/// over the mean change, over the points with `x > after`. About 1-2 for a smooth curve of
/// even steps; a spike of `k` times the typical step gives about `k`. `None` with fewer than
/// two changes or no change at all.
fn smoothness(points: &[(f64, f64)], after: f64) -> Option<f64> {
    let ys: Vec<f64> = points
        .iter()
        .filter(|&&(x, y)| x > after && x.is_finite() && y.is_finite())
        .map(|p| p.1)
        .collect();
    let steps: Vec<f64> = ys.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    if steps.len() < 2 {
        return None;
    }
    let mean = steps.iter().sum::<f64>() / steps.len() as f64;
    let largest = steps.iter().copied().fold(0.0, f64::max);
    (mean > 0.0).then(|| largest / mean)
}

/// The largest `|y_v(x) - y_ref(x)| / |y_ref(x)|` over the `reference` points with `x > after`,
/// `y_v` the `other` curve linearly interpolated at `x` ([`interpolate`]); reference points
/// outside the other curve's x range, or with `y_ref = 0`, are skipped. `None` if no point is
/// compared.
fn max_rel_diff(reference: &[(f64, f64)], other: &[(f64, f64)], after: f64) -> Option<f64> {
    let curve = by_x(other);
    reference
        .iter()
        .filter(|&&(x, y)| x > after && y != 0.0 && x.is_finite() && y.is_finite())
        .filter_map(|&(x, y)| interpolate(&curve, x).map(|yv| (yv - y).abs() / y.abs()))
        .filter(|d| d.is_finite())
        .fold(None, |max: Option<f64>, d| {
            Some(max.map_or(d, |m| m.max(d)))
        })
}

/// The finite `points` sorted by x; of several points at one x, the last (in the given order).
fn by_x(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    // A stable sort: points at one x stay in their order.
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(sorted.len());
    for p in sorted {
        match out.last_mut() {
            Some(last) if last.0 == p.0 => *last = p,
            _ => out.push(p),
        }
    }
    out
}

/// The curve through `curve` (sorted by x, each x once: [`by_x`]) at `x`, linearly
/// interpolated; `None` outside its x range.
fn interpolate(curve: &[(f64, f64)], x: f64) -> Option<f64> {
    let (first, last) = (curve.first()?, curve.last()?);
    if x < first.0 || x > last.0 {
        return None;
    }
    let i = curve.partition_point(|p| p.0 < x);
    let b = curve[i];
    if b.0 == x {
        return Some(b.1);
    }
    // x > first.0, so i >= 1.
    let a = curve[i - 1];
    Some(a.1 + (x - a.0) / (b.0 - a.0) * (b.1 - a.1))
}

/// The `(h, error)` points of a variant's converged runs.
fn points_of(runs: &[RunRecord], variant: &str) -> Vec<(f64, f64)> {
    runs.iter()
        .filter(|r| r.variant == variant && r.converged)
        .filter_map(|r| r.error.map(|e| (r.h, e)))
        .collect()
}

/// One progress line.
fn progress_line(metric: &str, r: &RunRecord) -> String {
    let result = match (r.converged, r.error) {
        (true, Some(e)) => format!("{metric} {e:.4e}"),
        _ => format!(
            "FAILED ({})",
            r.message.as_deref().unwrap_or("not converged")
        ),
    };
    format!(
        "  {} level {} h {:.4}: {result}, {} Newton its, {:.2} s",
        r.variant, r.level, r.h, r.newton_its, r.seconds
    )
}

/// The runs scored by their curves ([`Study::write_curves`]): at the last level, every variant
/// but the reference has its curve's difference to the reference as its error (none when its
/// curve has no overlap with the reference's); the reference (the truth of the comparison) and
/// the other levels have none, so they are not on the Pareto front.
fn curve_scores(
    runs: &[RunRecord],
    curves: &Curves,
    figures: &CurveFigures,
    last_level: usize,
) -> Vec<RunRecord> {
    runs.iter()
        .map(|r| {
            let difference = figures
                .differences
                .iter()
                .find(|(name, _)| *name == r.variant)
                .and_then(|(_, d)| *d)
                .filter(|_| r.level == last_level && r.variant != curves.reference);
            RunRecord {
                error: difference,
                converged: r.converged && difference.is_some(),
                ..r.clone()
            }
        })
        .collect()
}

/// Turns the runs' metrics into errors against the finest run of variant `reference` (at
/// level `finest`): `|m - m_ref| / |m_ref|` for every converged run; the reference run itself
/// keeps no error (it is the truth), and when the reference run failed or its metric is 0 no
/// run has one. Returns each run's metric as it was (`None` for a run without one) and the
/// truth `m_ref` (`None` when there is none).
fn errors_against_finest(
    runs: &mut [RunRecord],
    reference: &str,
    finest: usize,
) -> (Vec<Option<f64>>, Option<f64>) {
    let values: Vec<Option<f64>> = runs
        .iter()
        .map(|r| r.error.filter(|_| r.converged))
        .collect();
    let truth = runs
        .iter()
        .zip(&values)
        .find(|(r, _)| r.variant == reference && r.level == finest)
        .and_then(|(_, v)| *v)
        .filter(|&m| m != 0.0 && m.is_finite());
    for (r, value) in runs.iter_mut().zip(&values) {
        let is_truth = r.variant == reference && r.level == finest;
        r.error = match (truth, value) {
            (Some(m_ref), Some(m)) if !is_truth => Some((m - m_ref).abs() / m_ref.abs()),
            _ => None,
        };
    }
    (values, truth)
}

/// Whether a run's error ends the study rather than failing the run: an error that need not
/// reach every rank alike, and a file the run could not write ([`Error::Output`]: a full disk,
/// a folder without write permission, which the next runs would meet too). It is returned as
/// a rank's own error ([`Study::run_error`]), so on several ranks the job is aborted with it,
/// whatever the other ranks are doing.
fn ends_study(e: &Error) -> bool {
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

/// `study.csv` of the runs so far.
fn study_csv(runs: &[RunRecord]) -> String {
    let mut out = String::from(
        "variant,level,h,ranks,error,seconds,seconds_slowest,newton_its,converged,augmentations,\
         peak_memory_mb,on_front\n",
    );
    for r in runs {
        // Exponent form: errors at round-off would print as 0.0000000000001767...
        let error = r.error.map(|e| format!("{e:e}")).unwrap_or_default();
        let memory = r
            .peak_memory_mb
            .map(|m| format!("{m:.1}"))
            .unwrap_or_default();
        // Variant names are restricted to [A-Za-z0-9_-]: no quoting needed.
        let _ = writeln!(
            out,
            "{},{},{},{},{error},{},{},{},{},{},{memory},{}",
            r.variant,
            r.level,
            r.h,
            r.ranks,
            r.seconds,
            r.seconds_slowest,
            r.newton_its,
            r.converged,
            r.augmentations,
            r.on_front
        );
    }
    out
}

/// When two runs count as equal on the Pareto front (the study keys of the same names).
#[derive(Clone, Copy, Debug)]
pub struct Ties {
    /// Errors at or below this are equal.
    pub error_floor: f64,
    /// Errors that differ by at most this fraction of the larger are equal.
    pub error_noise: f64,
    /// Wall times that differ by at most this fraction of the larger are equal.
    pub time_noise: f64,
}

impl Ties {
    /// Only equal errors and equal times are equal.
    pub const EXACT: Ties = Ties {
        error_floor: 0.0,
        error_noise: 0.0,
        time_noise: 0.0,
    };
}

/// The runs on the Pareto front of error against wall time: converged runs with a finite
/// error that no other such run beats in both (no more time and no larger error, one of them
/// strictly), with the equalities of `ties`. Indices into `runs`, ascending.
pub fn pareto_front(runs: &[RunRecord], ties: Ties) -> Vec<usize> {
    let within = |noise: f64, a: f64, b: f64| (a - b).abs() <= noise * a.max(b);
    // `(strictly less, no more)` of `a` against `b`, with the tie of `noise`.
    let compare = |noise: f64, a: f64, b: f64| {
        if within(noise, a, b) {
            (false, true)
        } else {
            (a < b, a < b)
        }
    };
    let points: Vec<(usize, f64, f64)> = runs
        .iter()
        .enumerate()
        .filter(|(_, r)| r.converged)
        .filter_map(|(i, r)| {
            r.error
                .filter(|e| e.is_finite())
                .map(|e| (i, r.seconds, e.abs().max(ties.error_floor)))
        })
        .collect();
    points
        .iter()
        .filter(|&&(i, t, e)| {
            !points.iter().any(|&(j, tj, ej)| {
                let (faster, no_slower) = compare(ties.time_noise, tj, t);
                let (smaller, no_larger) = compare(ties.error_noise, ej, e);
                j != i && no_slower && no_larger && (faster || smaller)
            })
        })
        .map(|p| p.0)
        .collect()
}

/// A study's name: the study file's folder and stem, `<folder>_<stem>`
/// (`cases/sliding_blocks/study_quadrature.toml` is `sliding_blocks_study_quadrature`), or the
/// stem alone for a file without a named folder. The folder keeps the default output folders
/// (`out/<name>`) of different scenes' `study.toml` apart.
fn study_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    // The real folder (`..` resolved) of the file, which exists once the study is read.
    let folder = std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .ok()
        .and_then(|p| Some(p.parent()?.file_name()?.to_string_lossy().into_owned()));
    match folder {
        Some(folder) => format!("{folder}_{stem}"),
        None => stem,
    }
}

/// Resets the process's peak resident memory (`VmHWM`), where Linux allows it
/// (`/proc/self/clear_refs`, value 5); otherwise the peak read after a run is the process's.
fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The process's peak resident memory since the last reset, in MB (`VmHWM` of
/// `/proc/self/status`).
fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// The edits of one run, in order: the variant's, then the refinement's; each with the study
/// key it comes from.
fn edits<'a>(
    v: usize,
    variant: &'a VariantSpec,
    level: usize,
    refinement: &'a RefinementSpec,
) -> Vec<(String, &'a str, &'a toml::Value)> {
    let mut out = Vec::new();
    let mut tables = vec![
        (format!("variant[{v}].set"), &variant.set),
        (format!("refinement[{level}].set"), &refinement.set),
    ];
    if let Some(per_level) = variant.refinement_set.get(level) {
        tables.push((format!("variant[{v}].refinement_set[{level}]"), per_level));
    }
    for (key, table) in tables {
        for (path, value) in table {
            out.push((key.clone(), path.as_str(), value));
        }
    }
    out
}

/// Applies edits `(study key, dotted path, value)` to a case table, in order.
fn apply_sets(
    case: &mut toml::Table,
    edits: &[(String, &str, &toml::Value)],
) -> std::result::Result<(), String> {
    for (key, path, value) in edits {
        set_path(case, path, (*value).clone()).map_err(|m| format!("{key}.\"{path}\": {m}"))?;
    }
    Ok(())
}

/// Sets `value` at the dotted `path` of `table` (see the module docs for what may be created).
pub fn set_path(
    table: &mut toml::Table,
    path: &str,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let segments: Vec<&str> = path.split('.').collect();
    if segments.iter().any(|s| s.trim().is_empty()) {
        return Err("not a dotted path (an empty segment)".into());
    }
    set_in_table(table, &segments, 0, value)
}

/// An array index segment.
fn index(segment: &str) -> Option<usize> {
    segment.parse().ok()
}

/// [`set_path`] from segment `i` on, in the table at `segments[..i]`.
fn set_in_table(
    table: &mut toml::Table,
    segments: &[&str],
    i: usize,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let seg = segments[i];
    let at = segments[..=i].join(".");
    if index(seg).is_some() {
        let name = if i == 0 {
            "the case".to_string()
        } else {
            format!("'{}'", segments[..i].join("."))
        };
        return Err(format!(
            "{name} is a table, not an array: '{seg}' cannot index it"
        ));
    }
    if i + 1 == segments.len() {
        if let (Some(toml::Value::Array(_)), toml::Value::Table(_)) = (table.get(seg), &value) {
            return Err(format!(
                "a table would replace the array '{at}' (write dotted paths in quotes: \
                 \"{at}.0.key\" = value)"
            ));
        }
        table.insert(seg.to_string(), value);
        return Ok(());
    }
    if !table.contains_key(seg) {
        if let Some(k) = index(segments[i + 1]) {
            return Err(format!("no '{at}' in the case to index with {k}"));
        }
        table.insert(seg.to_string(), toml::Value::Table(toml::Table::new()));
    }
    let next = table.get_mut(seg).expect("present or just inserted");
    set_in_value(next, segments, i + 1, value)
}

/// [`set_path`] from segment `i` on, in the value at `segments[..i]`.
fn set_in_value(
    here: &mut toml::Value,
    segments: &[&str],
    i: usize,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let at = segments[..i].join(".");
    match here {
        toml::Value::Table(t) => set_in_table(t, segments, i, value),
        toml::Value::Array(items) => {
            let Some(k) = index(segments[i]) else {
                return Err(format!(
                    "'{at}' is an array: the next segment must be an index, not '{}'",
                    segments[i]
                ));
            };
            let n = items.len();
            let Some(item) = items.get_mut(k) else {
                let entries = if n == 1 { "entry" } else { "entries" };
                return Err(format!("'{at}' has {n} {entries}, no index {k}"));
            };
            if i + 1 == segments.len() {
                *item = value;
                Ok(())
            } else {
                set_in_value(item, segments, i + 1, value)
            }
        }
        other => Err(format!(
            "'{at}' is a value ({}), not a table",
            other.type_str()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of `variant` at `level` (h = 1 / (level + 1)) with these figures, the rest zero.
    fn record(
        variant: &str,
        level: usize,
        seconds: f64,
        error: Option<f64>,
        converged: bool,
    ) -> RunRecord {
        RunRecord {
            variant: variant.into(),
            level,
            h: 1.0 / (level + 1) as f64,
            ranks: 1,
            error,
            seconds,
            seconds_slowest: seconds,
            newton_its: 0,
            augmentations: 0,
            peak_memory_mb: None,
            converged,
            on_front: false,
            message: None,
            metrics: BTreeMap::new(),
        }
    }

    /// The default study names: the study file's folder and stem; the folder of a relative
    /// path with `..` is the real one.
    #[test]
    fn study_names_carry_their_folder() {
        let name = |p: &str| study_name(Path::new(p));
        assert_eq!(name("cases/hertz/study.toml"), "hertz_study");
        assert_eq!(
            name("/x/sliding_blocks/study_uzawa.toml"),
            "sliding_blocks_study_uzawa"
        );
        assert_eq!(name("/study.toml"), "study");
        // This file exists: `src/../src/study.rs` is in the folder `src`.
        let up = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/../src/study.rs");
        assert_eq!(study_name(&up), "src_study");
    }

    /// A study file that says nothing of them: errors within 1e-9 relative are equal, exact
    /// times only, one run each.
    #[test]
    fn study_file_defaults() {
        let file: StudyFile = toml::from_str("case = \"case.toml\"\nmetric = \"e\"\n").unwrap();
        assert_eq!(file.error_noise, 1e-9);
        assert_eq!(
            (file.error_floor, file.time_noise, file.repeat),
            (0.0, 0.0, 1)
        );
    }

    #[test]
    fn pareto_front_keeps_the_runs_nothing_beats() {
        let run = |variant: &str, seconds: f64, error: Option<f64>, converged: bool| {
            record(variant, 0, seconds, error, converged)
        };
        let runs = vec![
            run("fast_coarse", 1.0, Some(1e-2), true),
            run("slow_fine", 10.0, Some(1e-4), true),
            run("dominated", 5.0, Some(2e-2), true),
            run("tie_in_time", 10.0, Some(1e-3), true),
            run("failed", 0.1, None, false),
            run("middle", 3.0, Some(-1e-3), true),
        ];
        let ties = |error_floor: f64, error_noise: f64, time_noise: f64| Ties {
            error_floor,
            error_noise,
            time_noise,
        };
        let exact = Ties::EXACT;
        assert_eq!(pareto_front(&runs, exact), vec![0, 1, 5]);
        assert!(pareto_front(&[], exact).is_empty());
        // Below the floor, errors are equal: the slow fine run is beaten by the fast one.
        assert_eq!(pareto_front(&runs, ties(1e-2, 0.0, 0.0)), vec![0]);
        // Two runs doing the same work, 4 % apart: the slower is beaten without a noise margin
        // and kept with one; a time tie still loses to a smaller error.
        let twins = vec![
            run("defaults", 14.6, Some(7.5e-6), true),
            run("same_work", 14.0, Some(7.5e-6), true),
            run("finer_same_time", 14.3, Some(1e-6), true),
        ];
        assert_eq!(pareto_front(&twins[..2], exact), vec![1]);
        assert_eq!(pareto_front(&twins[..2], ties(0.0, 0.0, 0.1)), vec![0, 1]);
        assert_eq!(pareto_front(&twins, ties(0.0, 0.0, 0.1)), vec![2]);
        // The same integrals in another order (the Hertz study's two pallet splits at level 1):
        // the slower run's error is smaller in the 12th digit. It stays on the front when every
        // digit counts, and is beaten within a relative error noise; a real difference in error
        // (1e-6 relative) still keeps it.
        let reordered = vec![
            run("centroid", 11.65, Some(7.568973499695767e-3), true),
            run("fan", 9.35, Some(7.568973499702128e-3), true),
            run("finer", 11.65, Some(7.568966e-3), true),
        ];
        assert_eq!(pareto_front(&reordered[..2], exact), vec![0, 1]);
        assert_eq!(pareto_front(&reordered[..2], ties(0.0, 1e-9, 0.0)), vec![1]);
        assert_eq!(pareto_front(&reordered, ties(0.0, 1e-9, 0.0)), vec![1, 2]);
        // Both noises at once: equal times and equal errors beat neither.
        assert_eq!(
            pareto_front(&reordered[..2], ties(0.0, 1e-9, 0.3)),
            vec![0, 1]
        );
    }

    /// Errors against the finest run: relative differences of the metric to the reference
    /// variant's run at the last level, which itself has none; no errors at all when that run
    /// failed or its metric is 0; the metrics as they were are returned.
    #[test]
    fn errors_against_the_finest_run() {
        let run = |variant: &str, level: usize, value: f64, converged: bool| {
            record(variant, level, 1.0, Some(value), converged)
        };
        let study = || {
            vec![
                run("hex8", 0, 1.2, true),
                run("hex8", 1, 1.05, true),
                run("hex27", 0, 0.9, true),
                run("hex27", 1, -1.0, true),
                run("broken", 1, 7.0, false),
            ]
        };
        let mut runs = study();
        let (values, truth) = errors_against_finest(&mut runs, "hex27", 1);
        assert_eq!(truth, Some(-1.0));
        let errors: Vec<Option<f64>> = runs.iter().map(|r| r.error).collect();
        let close = |e: Option<f64>, want: f64| (e.unwrap() - want).abs() < 1e-15;
        assert!(close(errors[0], 2.2) && close(errors[1], 2.05) && close(errors[2], 1.9));
        assert_eq!(errors[3], None, "the truth has no error");
        assert_eq!(errors[4], None, "a failed run has none");
        assert_eq!(
            values,
            vec![Some(1.2), Some(1.05), Some(0.9), Some(-1.0), None]
        );

        // The reference run failed (or its metric is 0): no run has an error.
        for (converged, value) in [(false, 1.0), (true, 0.0)] {
            let mut runs = study();
            runs[3] = run("hex27", 1, value, converged);
            assert_eq!(errors_against_finest(&mut runs, "hex27", 1).1, None);
            assert!(runs.iter().all(|r| r.error.is_none()));
        }
    }

    #[test]
    fn smoothness_is_one_for_even_steps_and_flags_a_spike() {
        let even: Vec<(f64, f64)> = (0..10)
            .map(|i| (f64::from(i), 2.0 * f64::from(i)))
            .collect();
        assert_eq!(smoothness(&even, -1.0), Some(1.0));
        // One step of 10 among eight of 2: mean 26/9, largest 10.
        let mut spiky = even.clone();
        for p in spiky.iter_mut().skip(5) {
            p.1 += 8.0;
        }
        let s = smoothness(&spiky, -1.0).unwrap();
        assert!((s - 90.0 / 26.0).abs() < 1e-12, "{s}");
        // Only the points after x = 4.5 count: the spike at 4 -> 5 is left out.
        assert_eq!(smoothness(&spiky, 4.5), Some(1.0));
        assert_eq!(smoothness(&even[..2], -1.0), None);
        assert_eq!(
            smoothness(&[(0.0, 1.0), (1.0, 1.0), (2.0, 1.0)], -1.0),
            None
        );
    }

    #[test]
    fn curve_legend_names_unconverged_steps_and_early_stops() {
        assert_eq!(curve_legend("a", &[(0.0, 1.0)], &[], false), "a");
        assert_eq!(
            curve_legend("b", &[(0.0, 1.0), (0.25, 2.0)], &[(0.25, 2.0)], true),
            "b: 1 unconverged steps (ringed), stopped at 0.250"
        );
        assert_eq!(curve_legend("c", &[], &[], true), "c: failed");
    }

    fn case() -> toml::Table {
        toml::from_str(
            r#"
name = "s"
[[mesh]]
element = "hex20"
n_circ = 2
[[mesh]]
element = "hex8"
[steps]
count = 1
"#,
        )
        .unwrap()
    }

    fn set(path: &str, v: toml::Value) -> std::result::Result<toml::Table, String> {
        let mut t = case();
        set_path(&mut t, path, v)?;
        Ok(t)
    }

    #[test]
    fn paths_reach_array_entries_and_tables() {
        let t = set("mesh.1.n_circ", 3.into()).unwrap();
        assert_eq!(t["mesh"][1]["n_circ"].as_integer(), Some(3));
        assert_eq!(t["mesh"][0]["n_circ"].as_integer(), Some(2));
        let t = set("mesh.0.element", "hex27".into()).unwrap();
        assert_eq!(t["mesh"][0]["element"].as_str(), Some("hex27"));
        let t = set("steps.count", 4.into()).unwrap();
        assert_eq!(t["steps"]["count"].as_integer(), Some(4));
        // Missing keys are created, tables too: the case parser validates them.
        let t = set("newton.max_it", 2.into()).unwrap();
        assert_eq!(t["newton"]["max_it"].as_integer(), Some(2));
        let t = set("mesh.0.n_rad", 2.into()).unwrap();
        assert_eq!(t["mesh"][0]["n_rad"].as_integer(), Some(2));
        let t = set("name", "other".into()).unwrap();
        assert_eq!(t["name"].as_str(), Some("other"));
    }

    #[test]
    fn impossible_paths_are_named() {
        let e = set("mesh.2.n_circ", 3.into()).unwrap_err();
        assert_eq!(e, "'mesh' has 2 entries, no index 2");
        let e = set("meshes.0.n_circ", 3.into()).unwrap_err();
        assert!(e.contains("no 'meshes'"), "{e}");
        let e = set("mesh.first.n_circ", 3.into()).unwrap_err();
        assert!(e.contains("'mesh' is an array"), "{e}");
        let e = set("name.x", 3.into()).unwrap_err();
        assert!(e.contains("'name' is a value (string)"), "{e}");
        let e = set("mesh.0.n_circ.x", 3.into()).unwrap_err();
        assert!(e.contains("'mesh.0.n_circ' is a value (integer)"), "{e}");
        let e = set("steps.0", 3.into()).unwrap_err();
        assert!(e.contains("'steps' is a table"), "{e}");
        let e = set("mesh..x", 3.into()).unwrap_err();
        assert!(e.contains("empty segment"), "{e}");
        let nested: toml::Value =
            toml::from_str::<toml::Table>("a = { \"0\" = { n = 1 } }").unwrap()["a"].clone();
        let e = set("mesh", nested).unwrap_err();
        assert!(e.contains("in quotes"), "{e}");
    }

    #[test]
    fn later_edits_win_and_errors_name_the_key() {
        let mut t = case();
        let (a, b) = (toml::Value::from(3), toml::Value::from(4));
        let edits = vec![
            ("variant[0].set".to_string(), "mesh.0.n_circ", &a),
            ("refinement[1].set".to_string(), "mesh.0.n_circ", &b),
        ];
        apply_sets(&mut t, &edits).unwrap();
        assert_eq!(t["mesh"][0]["n_circ"].as_integer(), Some(4));
        let bad = vec![("refinement[1].set".to_string(), "mesh.7.n_circ", &a)];
        let e = apply_sets(&mut t, &bad).unwrap_err();
        assert!(
            e.starts_with("refinement[1].set.\"mesh.7.n_circ\": 'mesh'"),
            "{e}"
        );
    }

    #[test]
    fn csv_rows() {
        let r = RunRecord {
            variant: "hex8".into(),
            level: 1,
            h: 0.5,
            ranks: 2,
            error: Some(0.125),
            seconds: 2.5,
            seconds_slowest: 3.0,
            newton_its: 1,
            augmentations: 2,
            peak_memory_mb: Some(12.5),
            converged: true,
            on_front: true,
            message: None,
            metrics: BTreeMap::new(),
        };
        let failed = RunRecord {
            error: None,
            converged: false,
            peak_memory_mb: None,
            on_front: false,
            message: Some("x".into()),
            ..r.clone()
        };
        assert_eq!(
            study_csv(&[r, failed]),
            "variant,level,h,ranks,error,seconds,seconds_slowest,newton_its,converged,\
             augmentations,peak_memory_mb,on_front\n\
             hex8,1,0.5,2,1.25e-1,2.5,3,1,true,2,12.5,true\n\
             hex8,1,0.5,2,,2.5,3,1,false,2,,false\n"
        );
    }

    #[test]
    fn curve_differences_interpolate_over_the_overlap() {
        let ninf = f64::NEG_INFINITY;
        let reference = [(0.0, 1.0), (1.0, 2.0), (2.0, 4.0), (3.0, 8.0)];
        // Between its points the other curve is linear: 2.625 at x = 1, 4.875 at x = 2; x = 0
        // and x = 3 are outside its range.
        let other = [(0.5, 1.5), (2.5, 6.0)];
        assert_eq!(max_rel_diff(&reference, &other, ninf), Some(0.3125));
        // Only x > after.
        assert_eq!(max_rel_diff(&reference, &other, 1.0), Some(0.21875));
        assert_eq!(max_rel_diff(&reference, &other, 2.0), None);
        // The same points: zero; in any order, of any sign.
        assert_eq!(max_rel_diff(&reference, &reference, ninf), Some(0.0));
        let neg: Vec<(f64, f64)> = reference.iter().rev().map(|p| (-p.0, -p.1)).collect();
        let twice: Vec<(f64, f64)> = neg.iter().map(|p| (p.0, 2.0 * p.1)).collect();
        assert_eq!(max_rel_diff(&neg, &twice, ninf), Some(1.0));
        // No overlap, no points, or only y_ref = 0: nothing to compare.
        assert_eq!(
            max_rel_diff(&reference, &[(5.0, 1.0), (6.0, 1.0)], ninf),
            None
        );
        assert_eq!(max_rel_diff(&reference, &[], ninf), None);
        assert_eq!(max_rel_diff(&[], &reference, ninf), None);
        assert_eq!(max_rel_diff(&[(1.0, 0.0)], &reference, ninf), None);
        // One point of the other curve: compared at that x only.
        assert_eq!(max_rel_diff(&reference, &[(1.0, 3.0)], ninf), Some(0.5));
    }

    #[test]
    fn curves_keep_the_last_point_at_one_x() {
        // A first phase at x = 0 (compression before sliding), then x grows.
        let pts = [
            (0.0, 0.0),
            (0.0, 5.0),
            (0.0, 10.0),
            (0.5, 12.0),
            (1.0, f64::NAN),
        ];
        let curve = by_x(&pts);
        assert_eq!(curve, vec![(0.0, 10.0), (0.5, 12.0)]);
        assert_eq!(interpolate(&curve, 0.0), Some(10.0));
        assert_eq!(interpolate(&curve, 0.25), Some(11.0));
        assert_eq!(interpolate(&curve, 0.5), Some(12.0));
        assert_eq!(interpolate(&curve, 0.6), None);
        assert_eq!(interpolate(&curve, -0.1), None);
        assert_eq!(interpolate(&[], 0.0), None);
        // Unsorted input.
        let curve = by_x(&[(2.0, 4.0), (0.0, 0.0), (1.0, 1.0)]);
        assert_eq!(interpolate(&curve, 1.5), Some(2.5));
    }
}
