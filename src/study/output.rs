//! What a study writes (in `--out DIR`, default `out/<study name>`; written by rank 0):
//!
//! - `runs/<variant>/<level>/`: each run's own outputs (`level` = index of the refinement),
//!   emptied before the run, so that nothing an earlier study left there passes for its own.
//! - `study.csv`: one row per run, rewritten after every run: `variant, level, h, ranks,
//!   error` (the metric, or the largest of the metrics; with `finest_reference` the relative
//!   difference to the finest run's, rewritten once every run is done; empty for a failed
//!   run), `seconds` (wall clock; with `repeat`, the fastest of the run's converged repeats),
//!   `seconds_slowest` (the slowest of them), `newton_its` (total over the steps that
//!   converged), `converged` (`true`/`false`), `augmentations` (Uzawa, over the steps),
//!   `peak_memory_mb` (peak resident memory of the run, largest over the ranks:
//!   [`crate::study::one_run`]), `on_front` ([`crate::study::pareto`]).
//! - `summary.json` ([`Summary`]): `case` = the study name (the study file's folder and stem,
//!   `contact_patch_study` for `cases/contact_patch/study.toml`: the studies of one scene, and
//!   the `study.toml` of every scene, get folders of their own), `converged` = every run
//!   converged, `metrics`: `slope_<variant>` (least-squares slope of log(error) against log(h)
//!   over the variant's converged runs, when there are two or more) and
//!   `error_<variant>_<level>`; for every converged run, each metric of its own `summary.json`
//!   as `<metric>_<variant>_<level>` (`max_newton_its_case1_0`,
//!   `max_augmentations_per_step_case1_0`, `rel_error_peak_pressure_hex20_2`, ...), its wall
//!   time `seconds_<variant>_<level>` and its peak memory `peak_memory_mb_<variant>_<level>`,
//!   so that expectations can bound them (`max_newton_its_* <= 8`); plus `failed_runs`, with
//!   `finest_reference` the values `value_<variant>_<level>` ([`crate::study::finest`]), and
//!   with `[curves]` `curve_max_rel_diff_<variant>` and `smoothness_<variant>`
//!   ([`crate::study::curves`], added once every run is done); `on_front_<variant>_<level>` and
//!   `default_on_front` ([`crate::study::pareto`]); `timings.total`; `message` lists the failed
//!   runs. Rewritten after every run.
//! - `convergence.png`, `convergence.svg`: the log-log plot of error against h, one line per
//!   variant, the slopes in the legend ([`plot::Figure::loglog`]); only with 2 or more
//!   refinements.
//! - With `[curves]`: `curves.png`, `curves.svg` ([`crate::study::curves`]).
//! - `pareto.png`, `pareto.svg`: the error against wall time, the Pareto front ringed
//!   ([`crate::study::pareto`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::file::Study;
use crate::error::Result;
use crate::io::output::Summary;
use crate::io::plot;

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
    /// On the Pareto front of error against wall time (see [`crate::study::pareto_front`]).
    pub on_front: bool,
    /// Why the run failed.
    pub message: Option<String>,
    /// The metrics of the run's own `summary.json`, for a converged run, on the ranks that ran
    /// it (read on rank 0 only, where the study summary is made).
    pub metrics: BTreeMap<String, f64>,
}

impl RunRecord {
    /// The record of a run before its result is known: no error, no iterations, not
    /// converged, not on the front.
    pub(super) fn new(
        variant: &str,
        level: usize,
        h: f64,
        ranks: usize,
        seconds: f64,
        peak_memory_mb: Option<f64>,
    ) -> RunRecord {
        RunRecord {
            variant: variant.to_string(),
            level,
            h,
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
        }
    }
}
impl Study {
    /// The study summary of the runs so far.
    pub(super) fn summary(&self, runs: &[RunRecord], ranks: usize, seconds: f64) -> Summary {
        let mut s = Summary {
            case: self.name.clone(),
            ranks,
            converged: runs.len() == self.total_runs() && runs.iter().all(|r| r.converged),
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
                add_run_metrics(&mut s, r);
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

    /// `convergence.png` and `.svg`: error against h, one line per variant (rank 0; with 2 or
    /// more refinements). Returns the progress note of the slopes.
    pub(super) fn write_convergence(&self, runs: &[RunRecord], out: &Path) -> Result<String> {
        let series: Vec<plot::Series> = self
            .variants
            .iter()
            .map(|v| plot::Series {
                name: v.name.clone(),
                points: points_of(runs, &v.name),
                ..Default::default()
            })
            .collect();
        let stem = out.join("convergence");
        let label = self.error_label();
        let figure = plot::Figure::new(&stem, &self.title, "mesh size h", &label);
        plot::print_warnings(figure.loglog(&series)?);
        let slopes: Vec<String> = self
            .variants
            .iter()
            .map(|v| {
                let s = plot::fitted_slope(&points_of(runs, &v.name));
                if s.is_finite() {
                    format!("{} {s:.3}", v.name)
                } else {
                    format!("{} (none)", v.name)
                }
            })
            .collect();
        Ok(format!("slopes {}", slopes.join(", ")))
    }
}

/// A converged run's own metrics, its wall time and its peak memory into the study summary `s`,
/// as `<name>_<variant>_<level>`.
fn add_run_metrics(s: &mut Summary, r: &RunRecord) {
    let own = r.metrics.iter().map(|(k, v)| (k.as_str(), *v));
    let measured = [
        ("seconds", Some(r.seconds)),
        ("peak_memory_mb", r.peak_memory_mb),
    ];
    let measured = measured.into_iter().filter_map(|(k, v)| Some((k, v?)));
    // A name already taken (a study metric, or the same name made from another metric and
    // variant: both may hold `_`) keeps its first value.
    for (name, value) in own.chain(measured).filter(|(_, v)| v.is_finite()) {
        s.metrics
            .entry(format!("{name}_{}_{}", r.variant, r.level))
            .or_insert(value);
    }
}

/// One progress line.
pub(super) fn progress_line(metric: &str, r: &RunRecord) -> String {
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

/// The `(h, error)` points of a variant's converged runs.
fn points_of(runs: &[RunRecord], variant: &str) -> Vec<(f64, f64)> {
    runs.iter()
        .filter(|r| r.variant == variant && r.converged)
        .filter_map(|r| r.error.map(|e| (r.h, e)))
        .collect()
}

/// `study.csv` of the runs so far.
pub(super) fn study_csv(runs: &[RunRecord]) -> String {
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

/// A run of `variant` at `level` (h = 1 / (level + 1)) with these figures, the rest zero.
#[cfg(test)]
pub(super) fn record(
    variant: &str,
    level: usize,
    seconds: f64,
    error: Option<f64>,
    converged: bool,
) -> RunRecord {
    let h = 1.0 / (level + 1) as f64;
    RunRecord {
        error,
        converged,
        ..RunRecord::new(variant, level, h, 1, seconds, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
