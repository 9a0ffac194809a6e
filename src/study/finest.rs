//! Errors against the finest run (`finest_reference`).
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

use super::file::Study;
use super::output::RunRecord;
use crate::io::output::Summary;

impl Study {
    /// The level of the finest refinement (the smallest h).
    pub(super) fn finest_level(&self) -> usize {
        (0..self.refinements.len())
            .min_by(|&a, &b| self.refinements[a].h.total_cmp(&self.refinements[b].h))
            .unwrap_or(0)
    }

    /// What a run's error is, for plots and notes: the metric, or with `finest_reference` its
    /// relative difference to the finest run's.
    pub(super) fn error_label(&self) -> String {
        match &self.finest_reference {
            Some(reference) => format!(
                "rel. diff. of {} to {reference} at h = {:.4e}",
                self.metric,
                self.refinements[self.finest_level()].h
            ),
            None => self.metric.clone(),
        }
    }

    /// With `finest_reference`, turns the runs' metrics into errors against the finest run's
    /// ([`errors_against_finest`]): returns the metrics as the runs reported them, and the
    /// study's failure when there is no truth (the finest run failed, or its metric is 0 or not
    /// finite). `None` without `finest_reference`.
    pub(super) fn against_finest(
        &self,
        runs: &mut [RunRecord],
    ) -> Option<(Vec<Option<f64>>, Option<String>)> {
        let reference = self.finest_reference.as_deref()?;
        let finest = self.finest_level();
        let (values, truth) = errors_against_finest(runs, reference, finest);
        let failed = truth.is_none().then(|| {
            format!(
                "study {}: the finest_reference run ({reference} at level {finest}) failed or \
                 its {} is 0 or not finite: no run has an error",
                self.name, self.metric
            )
        });
        Some((values, failed))
    }
}

/// Puts the runs' metrics as they reported them (`values`, from [`Study::against_finest`])
/// into the study summary: `value_<variant>_<level>`.
pub(super) fn add_values(summary: &mut Summary, runs: &[RunRecord], values: &[Option<f64>]) {
    for (r, value) in runs.iter().zip(values) {
        if let Some(value) = value {
            summary
                .metrics
                .insert(format!("value_{}_{}", r.variant, r.level), *value);
        }
    }
}

/// Turns the runs' metrics into errors against the finest run of variant `reference` (at
/// level `finest`): `|m - m_ref| / |m_ref|` for every converged run; the reference run itself
/// keeps no error (it is the truth), and when the reference run failed or its metric is 0 no
/// run has one. Returns each run's metric as it was (`None` for a run without one) and the
/// truth `m_ref` (`None` when there is none).
pub(super) fn errors_against_finest(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::output::record;

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
}
