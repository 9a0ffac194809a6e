//! Reading PETSc's performance summary (`-log_view :FILE`, the default ASCII format): the
//! number of ranks, the run's wall time and the time of every log stage.
//!
//! The parts read, as PETSc 3.18 writes them:
//!
//! ```text
//! mortar on a  named vm with 2 processors, by ...
//!                          Max       Max/Min     Avg       Total
//! Time (sec):           2.008e+01     1.000   2.008e+01
//! ...
//! Summary of Stages:   ----- Time ------  ----- Flop ------  ...
//!                         Avg     %Total     Avg     %Total  ...
//!  0:      Main Stage: 1.7161e+00   8.5%  6.6443e+09  21.6%  ...
//!  6: Mortar integration: 1.0816e+01  53.9%  ...
//! ```
//!
//! The run's time is the `Time (sec)` maximum over the ranks; a stage's time is the `Avg`
//! column of its line (the mean over the ranks; PETSc's stage table has no maximum). Stage
//! times are exclusive: a stage pushed inside another (the contact search inside the
//! assembly) counts only in the inner one.
//!
//! The number of Newton iterations is the count of the `SNESJacobianEval` event (one Jacobian
//! per Newton iteration), summed over the event tables of the stages. That holds for the
//! nonlinear scenes (checked against `summary.json`'s `total_newton_its` on the contact patch
//! and the scaling scene); a scene with a frozen tangent (linear materials, no contact) or one
//! whose first iteration reuses the predictor's Jacobian evaluates fewer Jacobians than it
//! takes iterations, and the count is then a lower bound:
//!
//! ```text
//! --- Event Stage 3: solve
//! SNESJacobianEval      66 1.0 1.4585e+01 1.0 ...
//! ```

use std::path::Path;

use crate::error::{Error, Result};

/// What a PETSc log says of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct PetscLog {
    /// The number of ranks ("with N processors", or "processes" as later PETSc versions say).
    pub ranks: usize,
    /// Wall time of the run (maximum over the ranks), seconds.
    pub seconds: f64,
    /// Every log stage in the table's order: name and time (mean over the ranks), seconds.
    pub stages: Vec<(String, f64)>,
    /// Newton iterations (`SNESJacobianEval` events); `None` when the log has no such event.
    pub newton_iterations: Option<usize>,
}

impl PetscLog {
    /// Reads a `-log_view` file; errors name the file and what is missing.
    pub fn read(path: &Path) -> Result<PetscLog> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        parse(&text).map_err(|msg| {
            Error::Other(format!(
                "{}: {msg} (is it the output of -log_view?)",
                path.display()
            ))
        })
    }

    /// The time of stage `name`, if the log has it.
    pub fn stage(&self, name: &str) -> Option<f64> {
        self.stages.iter().find(|(n, _)| n == name).map(|s| s.1)
    }
}

/// Parses the text of a `-log_view` summary.
pub fn parse(text: &str) -> std::result::Result<PetscLog, String> {
    let ranks = text
        .lines()
        .find_map(|l| {
            let (_, rest) = l.split_once(" with ")?;
            let n = rest.split_whitespace().next()?.parse::<usize>().ok()?;
            rest.split_whitespace()
                .nth(1)
                .filter(|w| w.starts_with("process"))
                .map(|_| n)
        })
        .ok_or("no line 'with N processors'")?;
    let seconds = text
        .lines()
        .find_map(|l| l.strip_prefix("Time (sec):"))
        .and_then(|rest| rest.split_whitespace().next()?.parse::<f64>().ok())
        .ok_or("no 'Time (sec):' line")?;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("'Time (sec):' is {seconds}, not a positive time"));
    }
    let mut lines = text
        .lines()
        .skip_while(|l| !l.starts_with("Summary of Stages:"));
    if lines.next().is_none() {
        return Err("no 'Summary of Stages' table".into());
    }
    let mut stages = Vec::new();
    // The column header, then one line per stage: "<index>: <name>: <avg time> <%> ...".
    for line in lines.skip(1) {
        let Some((index, rest)) = line.split_once(':') else {
            break;
        };
        if index.trim().parse::<usize>().is_err() {
            break;
        }
        let (name, figures) = rest
            .rsplit_once(": ")
            .ok_or_else(|| format!("stage line '{}' has no time", line.trim()))?;
        let time = figures
            .split_whitespace()
            .next()
            .and_then(|t| t.parse::<f64>().ok())
            .filter(|t| t.is_finite() && *t >= 0.0)
            .ok_or_else(|| format!("stage line '{}' has no time", line.trim()))?;
        stages.push((name.trim().to_string(), time));
    }
    if stages.is_empty() {
        return Err("the 'Summary of Stages' table is empty".into());
    }
    // PETSc ends the summary with the options table (or says there were none): a log
    // without it was cut short, and its event counts may be missing.
    let complete = text.lines().any(|l| {
        l.starts_with("#End of PETSc Option Table entries")
            || l.starts_with("#No PETSc Option Table entries")
    });
    if !complete {
        return Err("no option table at its end: the log is cut short".into());
    }
    Ok(PetscLog {
        ranks,
        seconds,
        stages,
        newton_iterations: event_count(text, "SNESJacobianEval"),
    })
}

/// The count of event `name` summed over the event tables of every stage (the first column
/// after the name, the maximum over the ranks); `None` when no table lists it.
fn event_count(text: &str, name: &str) -> Option<usize> {
    let tables = text
        .lines()
        .skip_while(|l| !l.starts_with("--- Event Stage"))
        .take_while(|l| !l.starts_with("Memory usage") && !l.starts_with("Object Type"));
    let counts: Vec<usize> = tables
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            (words.next() == Some(name)).then(|| words.next()?.parse().ok())?
        })
        .collect();
    let total: usize = counts.iter().sum();
    (total > 0).then_some(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &str = "\
------------------------------------------------------------------ PETSc Performance Summary: ---

target/release/mortar on a  named vm with 2 processors, by Unknown Sat Nov 21 14:11:36 2026
Using Petsc Release Version 3.18.5, Feb 27, 2023

                         Max       Max/Min     Avg       Total
Time (sec):           2.008e+01     1.000   2.000e+01
Objects:              3.330e+02     1.000   3.330e+02

Summary of Stages:   ----- Time ------  ----- Flop ------  --- Messages ---
                        Avg     %Total     Avg     %Total    Count   %Total
 0:      Main Stage: 1.7161e+00   8.5%  6.6443e+09  21.6%  0.000e+00   0.0%
 1:           setup: 1.1471e-02   0.1%  2.3640e+03   0.0%  0.000e+00   0.0%
 6: Mortar integration: 1.0816e+01  53.9%  0.0000e+00   0.0%  0.000e+00   0.0%

------------------------------------------------------------------------------------------
See the 'Profiling' chapter of the users' manual for details on interpreting output.
Event                Count      Time (sec)     Flop
                   Max Ratio  Max     Ratio   Max  Ratio
------------------------------------------------------------------------------------------

--- Event Stage 0: Main Stage

KSPSolve              12 1.0 9.4959e-02 1.0 7.02e+10 1.0

--- Event Stage 3: solve

SNESJacobianEval      66 1.0 1.4585e+01 1.0 2.29e+08 1.0

--- Event Stage 6: Mortar integration

SNESJacobianEval       4 1.0 1.4585e+01 1.0 2.29e+08 1.0

Memory usage is given in bytes:

Object Type          Creations   Destructions     Memory  Descendants' Mem.
--- Event Stage 0: Main Stage
SNESJacobianEval       1              1         1000     0.
#PETSc Option Table entries:
-log_view :log_2.txt
#End of PETSc Option Table entries
";

    #[test]
    fn reads_ranks_time_and_stages() {
        let log = parse(LOG).unwrap();
        assert_eq!(log.ranks, 2);
        assert_eq!(log.seconds, 20.08);
        assert_eq!(
            log.stages,
            vec![
                ("Main Stage".to_string(), 1.7161),
                ("setup".to_string(), 0.011471),
                ("Mortar integration".to_string(), 10.816),
            ]
        );
        assert_eq!(log.stage("setup"), Some(0.011471));
        // The event tables' counts, not the object table's.
        assert_eq!(log.newton_iterations, Some(70));
        let without = LOG.replace("SNESJacobianEval", "SNESOther");
        assert_eq!(parse(&without).unwrap().newton_iterations, None);
        // A count of 0 is no count (no division by zero downstream).
        let zero = LOG
            .replace("SNESJacobianEval      66", "SNESJacobianEval       0")
            .replace("SNESJacobianEval       4", "SNESJacobianEval       0");
        assert_eq!(parse(&zero).unwrap().newton_iterations, None);
        let one = LOG.replace("with 2 processors", "with 1 processor");
        assert_eq!(parse(&one).unwrap().ranks, 1);
    }

    #[test]
    fn incomplete_logs_are_refused() {
        assert!(parse("hello").unwrap_err().contains("processors"));
        let no_table = LOG.replace("Summary of Stages:", "Summary:");
        assert!(parse(&no_table).unwrap_err().contains("Summary of Stages"));
        let no_time = LOG.replace("Time (sec):", "Tiempo:");
        assert!(parse(&no_time).unwrap_err().contains("Time (sec)"));
        let nan_time = LOG.replace("Time (sec):           2.008e+01", "Time (sec): nan");
        assert!(parse(&nan_time).unwrap_err().contains("Time (sec)"));
        let nan_stage = LOG.replace("Mortar integration: 1.0816e+01", "Mortar integration: nan");
        assert!(parse(&nan_stage)
            .unwrap_err()
            .contains("Mortar integration"));
        // Cut short before the options table PETSc prints last (its event counts may be lost).
        let cut = &LOG[..LOG.find("Memory usage").unwrap()];
        assert!(parse(cut).unwrap_err().contains("cut short"));
        let no_options = LOG.replace(
            "#PETSc Option Table entries:\n-log_view :log_2.txt\n#End of PETSc Option Table entries",
            "#No PETSc Option Table entries",
        );
        assert!(parse(&no_options).is_ok());
    }
}
