//! The Pareto front of error against wall time: `pareto.png`, `pareto.svg`, the error against
//! wall time on log-log axes ([`plot::Figure::loglog_points`]), every converged run a point,
//! its **Pareto front** ringed: the runs that no other run beats in both (no more time and no
//! larger error, one of them strictly; errors at or below the study's `error_floor` count as
//! equal, and so do errors within its `error_noise` of each other (relative: far below any
//! discretization error) and wall times within its `time_noise`; [`pareto_front`]); variants
//! with `reference_only = true` are plotted but not candidates.
//!
//! Without `[curves]` the error is the metric (with `finest_reference`, its relative difference
//! to the finest run's: [`crate::study::finest`]); with `[curves]` (no exact solution: the
//! reference variant is the truth) it is a variant's `curve_max_rel_diff` at the last level,
//! and the reference is not on the plot ([`crate::study::curves`]).
//!
//! The summary gets `on_front_<variant>_<level>` (1 or 0) and, for the default variant (the
//! first with no edits, no `refinement_set`, no `petsc`, no `ranks` and not `reference_only`:
//! the case file as it is, [`VariantSpec::is_default`]), `default_on_front`, the share of its
//! runs on the front (its failed runs counted, off it; not its `finest_reference` run, the
//! truth); the closing line says it. `study.csv`'s `on_front` column has the flags.
//!
//! [`VariantSpec::is_default`]: crate::study::VariantSpec::is_default

use std::path::Path;

use super::file::Study;
use super::output::RunRecord;
use crate::error::Result;
use crate::io::output::Summary;
use crate::io::plot;

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

impl Study {
    /// The runs on the Pareto front ([`pareto_front`] with the study's `error_floor`,
    /// `error_noise` and `time_noise`), among the runs of the variants that are choices (not
    /// `reference_only`).
    pub(super) fn front(&self, runs: &[RunRecord]) -> Vec<usize> {
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

    /// The Pareto front of error against wall time (the flags are set on `runs`, labelled
    /// `metric`): `pareto.png` and `.svg` (every converged run a point, one line per variant,
    /// the front ringed), the summary's `on_front_<variant>_<level>` and, for the default
    /// variant ([`VariantSpec::is_default`]), `default_on_front` (the share of its runs on the
    /// front). Returns the progress note.
    ///
    /// [`VariantSpec::is_default`]: crate::study::VariantSpec::is_default
    pub(super) fn write_pareto(
        &self,
        runs: &[RunRecord],
        metric: &str,
        summary: &mut Summary,
        out: &Path,
    ) -> Result<String> {
        let stem = out.join("pareto");
        let title = format!(
            "{}: {metric} against wall time (ringed: Pareto front)",
            self.name
        );
        let figure = plot::Figure::new(&stem, &title, "wall time (s)", metric);
        plot::print_warnings(figure.loglog_points(&self.pareto_series(runs))?);
        for r in runs.iter().filter(|r| r.converged && r.error.is_some()) {
            summary.metrics.insert(
                format!("on_front_{}_{}", r.variant, r.level),
                f64::from(u8::from(r.on_front)),
            );
        }
        let front = runs.iter().filter(|r| r.on_front).count();
        let mut note = format!("Pareto front of {metric} against wall time: {front} run(s)");
        if let Some(defaults) = self.default_on_front(runs, summary) {
            note.push_str(&defaults);
        }
        summary.write(&out.join("summary.json"))?;
        Ok(note)
    }

    /// The plot's series: per variant its converged runs' points, those on the front flagged.
    fn pareto_series(&self, runs: &[RunRecord]) -> Vec<plot::Series> {
        // Errors at or below the floor are plotted at the floor (they count as equal; an exact
        // 0 would not show on log axes).
        let point = |r: &RunRecord| r.error.map(|e| (r.seconds, e.abs().max(self.error_floor)));
        self.variants
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
            .collect()
    }

    /// `default_on_front` into the summary, the share of the default variant's runs on the
    /// front, and the note saying it; none without a default variant (or one that is a
    /// reference) or without candidate runs of it.
    fn default_on_front(&self, runs: &[RunRecord], summary: &mut Summary) -> Option<String> {
        let d = self
            .variants
            .iter()
            .find(|v| v.is_default())
            .filter(|d| !self.is_reference(d))?;
        // The candidates among the runs of the defaults, the failed ones counted (off the
        // front): with [curves] those of the last level, where curves are scored (the runs
        // below it carry no error, and `converged = false`: `curve_scores`); otherwise every
        // run but the truth (the finest_reference run).
        let finest = self.finest_level();
        let last = self.refinements.len() - 1;
        let candidate = |r: &RunRecord| match &self.curves {
            Some(_) => r.level == last,
            None => {
                !(self.finest_reference.as_deref() == Some(r.variant.as_str()) && r.level == finest)
            }
        };
        let mine: Vec<&RunRecord> = runs
            .iter()
            .filter(|r| r.variant == d.name && candidate(r))
            .collect();
        if mine.is_empty() {
            return None;
        }
        let on = mine.iter().filter(|r| r.on_front).count();
        summary
            .metrics
            .insert("default_on_front".into(), on as f64 / mine.len() as f64);
        Some(format!(
            "; the defaults (variant '{}') have {on} of {} runs on it",
            d.name,
            mine.len()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::output::record;

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
}
