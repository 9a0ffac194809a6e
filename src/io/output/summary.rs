//! `summary.json`: what a run did, for scripts and CI.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{content_error, write_atomic};
use crate::{Error, Result};

/// One load step.
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct StepRecord {
    pub step: usize,
    pub load: f64,
    pub newton_its: usize,
    /// Times this step was cut before converging.
    pub cut: usize,
    pub converged: bool,
    /// Uzawa augmentations of the step (0 without augmented interfaces).
    #[serde(default)]
    pub augmentations: usize,
}

/// The run summary.
#[derive(Serialize, Deserialize, Debug, Clone, Default, PartialEq)]
pub struct Summary {
    pub case: String,
    pub ranks: usize,
    /// Every step converged and the run reached the full load.
    pub converged: bool,
    /// The run reached the full load, possibly through steps accepted without convergence
    /// (`steps.on_failure = "continue"`; counted in the metric `unconverged_steps`).
    #[serde(default)]
    pub completed: bool,
    pub steps: Vec<StepRecord>,
    /// Wall-clock seconds by phase.
    pub timings: BTreeMap<String, f64>,
    pub metrics: BTreeMap<String, f64>,
    /// Why the run failed or stopped (a step that did not converge, an interruption, the error
    /// that ended it), if it did.
    pub message: Option<String>,
    /// Peak resident memory of each rank's process, in MB (`crate::memory`), at the end of the
    /// run; empty where the system does not say.
    #[serde(default)]
    pub peak_memory_mb: Vec<f64>,
    /// Each rank's wall-clock seconds in the contact phases (search, mortar integration and
    /// contact assembly): how evenly the contact work is dealt out.
    #[serde(default)]
    pub contact_seconds_per_rank: Vec<f64>,
}

impl Summary {
    /// Checks that every number is finite (JSON has no NaN), naming the offender.
    fn check(&self, path: &Path) -> Result<()> {
        for (kind, map) in [("metric", &self.metrics), ("timing", &self.timings)] {
            if let Some((k, v)) = map.iter().find(|(_, v)| !v.is_finite()) {
                return Err(content_error(
                    path,
                    format!("{kind} '{k}' is not finite ({v})"),
                ));
            }
        }
        if let Some(s) = self.steps.iter().find(|s| !s.load.is_finite()) {
            return Err(content_error(
                path,
                format!("load of step {} is not finite ({})", s.step, s.load),
            ));
        }
        Ok(())
    }

    /// Writes the summary as pretty JSON, atomically. A non-finite metric, timing or load is an
    /// error naming it, and nothing is written.
    pub fn write(&self, path: &Path) -> Result<()> {
        self.check(path)?;
        let mut json = serde_json::to_string_pretty(self)
            .map_err(|e| content_error(path, format!("cannot serialize summary: {e}")))?;
        json.push('\n');
        write_atomic(path, json.as_bytes())
    }

    /// Reads a summary written by [`Summary::write`].
    pub fn read(path: &Path) -> Result<Summary> {
        let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        serde_json::from_slice(&text).map_err(|e| content_error(path, format!("bad summary: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::Scratch;
    use super::*;

    fn sample() -> Summary {
        Summary {
            case: "hertz".into(),
            ranks: 4,
            converged: false,
            completed: false,
            steps: vec![
                StepRecord {
                    step: 1,
                    load: 0.1,
                    newton_its: 5,
                    cut: 0,
                    converged: true,
                    augmentations: 0,
                },
                StepRecord {
                    step: 2,
                    load: 1.0 / 3.0,
                    newton_its: 12,
                    cut: 2,
                    converged: false,
                    augmentations: 3,
                },
            ],
            timings: [("assembly".to_string(), 1.25), ("solve".to_string(), 3e-3)].into(),
            metrics: [("max_penetration".to_string(), -1.5e-9)].into(),
            message: Some("Newton diverged in step 2".into()),
            peak_memory_mb: vec![512.5, 498.0],
            contact_seconds_per_rank: vec![3.5, 3.25],
        }
    }

    #[test]
    fn summary_round_trip() {
        let dir = Scratch::new("summary");
        let p = dir.path("summary.json");
        let s = sample();
        s.write(&p).unwrap();
        assert_eq!(Summary::read(&p).unwrap(), s);
        let ok = Summary {
            message: None,
            ..Summary::default()
        };
        ok.write(&p).unwrap();
        assert_eq!(Summary::read(&p).unwrap(), ok);
        assert!(std::fs::read_to_string(&p)
            .unwrap()
            .contains("\"message\": null"));
        assert_eq!(dir.listing(), vec!["summary.json".to_string()]);
    }

    #[test]
    fn non_finite_metric_rejected() {
        let dir = Scratch::new("summary-nan");
        let p = dir.path("summary.json");
        let mut s = sample();
        s.metrics.insert("energy".into(), f64::NAN);
        let msg = s.write(&p).unwrap_err().to_string();
        assert!(msg.contains("metric 'energy'"), "{msg}");
        assert!(dir.listing().is_empty());
        std::fs::write(&p, "{ not json").unwrap();
        assert!(Summary::read(&p).is_err());
    }
}
