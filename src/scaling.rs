//! Strong scaling from PETSc logs: `mortar scaling LOG_1 LOG_2 ... [--out DIR]`.
//!
//! Each log is the `-log_view :FILE` summary of one run of the same scene on some number of
//! ranks (`mortar run CASE -log_view :log_1.txt`, `mpirun -n 2 mortar run CASE -log_view
//! :log_2.txt`). The runs' phases are PETSc log stages (the solver pushes them; see
//! `crate::petsc::log`), grouped as:
//!
//! | phase | log stages |
//! |---|---|
//! | contact search | `Contact search` |
//! | mortar integration | `Mortar integration` |
//! | contact assembly | `Contact assembly` |
//! | bulk assembly | `assembly` (the bulk elements, tied interfaces, PETSc's assembly) |
//! | linear solve | `solve` (SNES: the linear solves, norms and updates) |
//! | matrix pattern | `pattern` (the contact pattern's updates and the new matrices they make; none without contact) |
//! | output | `output` |
//! | start and setup | `Main Stage` (everything outside the other stages: PETSc's start, the
//! partitioning, the dof numbering, the load-step predictor's bulk work, linear solves and
//! factorizations) and `setup` |
//!
//! The contact stages count every contact evaluation, the reactions of the output included
//! (`summary.json` counts those of the steps' solves, the predictors' included, and the
//! predictor's linear solves in its `solve`). The case file is read and the mesh
//! built before PETSc starts, so that serial part is in no stage and not in the wall times.
//!
//! The speedup of a phase on run `k` is its time on the first run over its time on run `k`
//! (stage times are means over the ranks); the overall speedup is the ratio of the runs' wall
//! times (`Time (sec)`, the maximum over the ranks). A frictional scene may take a different
//! number of Newton iterations on 1 and 2 ranks (its path depends on round-off), so the table
//! also gives each run's Newton iterations (`SNESJacobianEval` events) and the speedup of the
//! wall time per Newton iteration. Outputs in `DIR` (default `out/scaling`):
//! `scaling.csv` (`phase,ranks,seconds,speedup`, the overall time as phase `total`; the
//! speedup empty for a phase a run did not have) and
//! `scaling.png`/`.svg` (time against ranks on log-log axes: the total, the ideal
//! `total_1 / ranks`, and the phases of `PLOTTED`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::io::output::write_atomic;
use crate::io::petsc_log::PetscLog;
use crate::io::plot;

/// The phases reported, each with the log stages it sums.
pub const PHASES: [(&str, &[&str]); 8] = [
    ("contact search", &["Contact search"]),
    ("mortar integration", &["Mortar integration"]),
    ("contact assembly", &["Contact assembly"]),
    ("bulk assembly", &["assembly"]),
    ("linear solve", &["solve"]),
    ("matrix pattern", &["pattern"]),
    ("output", &["output"]),
    ("start and setup", &["Main Stage", "setup"]),
];

/// The stages every run of `mortar run` has, contact or not (`crate::solver`).
const SOLVER_STAGES: [&str; 4] = ["setup", "assembly", "solve", "output"];

/// The phases drawn in the plot (the others are small or constant).
const PLOTTED: [&str; 4] = [
    "linear solve",
    "mortar integration",
    "contact assembly",
    "bulk assembly",
];

/// Scaling figures of several runs of one scene.
#[derive(Clone, Debug)]
pub struct Scaling {
    /// The runs, in the order given.
    pub runs: Vec<PetscLog>,
}

impl Scaling {
    /// Reads the logs (at least 2) and checks that they are runs of one scene by `mortar run`
    /// on strictly increasing rank counts (`Scaling::check`).
    pub fn read(logs: &[PathBuf]) -> Result<Scaling> {
        if logs.len() < 2 {
            return Err(Error::Other(format!(
                "scaling needs at least 2 PETSc logs, got {}",
                logs.len()
            )));
        }
        let runs = logs
            .iter()
            .map(|p| PetscLog::read(p))
            .collect::<Result<Vec<_>>>()?;
        let scaling = Scaling { runs };
        scaling
            .check()
            .map_err(|(k, msg)| Error::Other(format!("{}: {msg}", logs[k].display())))?;
        Ok(scaling)
    }

    /// The runs must be comparable, or the table would quietly show zeros and false speedups:
    /// every log has the solver's own stages ([`SOLVER_STAGES`]: a log of `mortar run`), the
    /// same stages as the first (the same scene; a log cut short in its stage table lacks
    /// some), Newton iterations in all or none, and rank counts strictly increasing (the
    /// reference, fewest ranks, first). The error gives the index of the log at fault.
    fn check(&self) -> std::result::Result<(), (usize, String)> {
        let first = &self.runs[0];
        for (k, run) in self.runs.iter().enumerate() {
            if let Some(missing) = SOLVER_STAGES.iter().find(|s| run.stage(s).is_none()) {
                return Err((
                    k,
                    format!("no log stage '{missing}': not a log of `mortar run`, or cut short"),
                ));
            }
            let names = |r: &PetscLog| r.stages.iter().map(|s| s.0.clone()).collect::<Vec<_>>();
            let (mine, theirs) = (names(run), names(first));
            if let Some(missing) = theirs
                .iter()
                .chain(&mine)
                .find(|s| run.stage(s).is_none() || first.stage(s).is_none())
            {
                return Err((
                    k,
                    format!(
                        "its log stages differ from the first log's (stage '{missing}' is in \
                         one only): logs of one scene are needed, none cut short"
                    ),
                ));
            }
            if run.newton_iterations.is_some() != first.newton_iterations.is_some() {
                return Err((
                    k,
                    "Newton iterations (SNESJacobianEval) in one log only: logs of one scene \
                     are needed, none cut short"
                        .into(),
                ));
            }
            if k > 0 && run.ranks <= self.runs[k - 1].ranks {
                return Err((
                    k,
                    format!(
                        "a run on {} rank(s) after one on {}: give the logs by strictly \
                         increasing rank count, the reference (fewest ranks) first",
                        run.ranks,
                        self.runs[k - 1].ranks
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The time of `phase` (one of [`PHASES`]) in run `k`: the sum of its stages.
    pub fn phase_seconds(&self, k: usize, phase: &str) -> f64 {
        let stages = PHASES
            .iter()
            .find(|(name, _)| *name == phase)
            .map_or(&[][..], |p| p.1);
        // (+ 0.0: an empty sum is -0.0.)
        stages
            .iter()
            .filter_map(|s| self.runs[k].stage(s))
            .sum::<f64>()
            + 0.0
    }

    /// The overall speedup of run `k` over the first run (wall times).
    pub fn speedup(&self, k: usize) -> f64 {
        self.runs[0].seconds / self.runs[k].seconds
    }

    /// The speedup of run `k` over the first run in wall time per Newton iteration; `None`
    /// when a log has no Newton iterations.
    pub fn speedup_per_newton_iteration(&self, k: usize) -> Option<f64> {
        let per_iteration = |r: &PetscLog| Some(r.seconds / r.newton_iterations? as f64);
        Some(per_iteration(&self.runs[0])? / per_iteration(&self.runs[k])?)
    }

    /// The table printed: one row per phase (and the total), the time of every run and the
    /// speedup of every run after the first.
    pub fn table(&self) -> String {
        let mut out = format!("{:<20}", "phase");
        for r in &self.runs {
            let _ = write!(out, "{:>14}", format!("{} rank(s) s", r.ranks));
        }
        for r in &self.runs[1..] {
            let _ = write!(out, "{:>14}", format!("speedup {}", r.ranks));
        }
        out.push('\n');
        for (phase, _) in PHASES {
            table_row(
                &mut out,
                phase,
                (0..self.runs.len())
                    .map(|k| self.phase_seconds(k, phase))
                    .collect(),
            );
        }
        table_row(
            &mut out,
            "total (wall)",
            self.runs.iter().map(|r| r.seconds).collect(),
        );
        if self.runs.iter().all(|r| r.newton_iterations.is_some()) {
            let _ = write!(out, "{:<20}", "Newton iterations");
            for r in &self.runs {
                let _ = write!(out, "{:>14}", r.newton_iterations.unwrap_or(0));
            }
            out.push('\n');
            table_row(
                &mut out,
                "wall per iteration",
                self.runs
                    .iter()
                    .map(|r| r.seconds / r.newton_iterations.unwrap_or(0) as f64)
                    .collect(),
            );
        }
        out
    }

    /// `scaling.csv`: `phase,ranks,seconds,speedup` (and the wall time per Newton iteration as
    /// phase `per_newton_iteration`, when the logs count them).
    pub fn csv(&self) -> String {
        let mut out = String::from("phase,ranks,seconds,speedup\n");
        for (k, r) in self.runs.iter().enumerate() {
            for (phase, _) in PHASES {
                let (first, mine) = (self.phase_seconds(0, phase), self.phase_seconds(k, phase));
                // (Empty when the run did not have the phase.)
                let speedup = ratio(first, mine).map_or(String::new(), |s| s.to_string());
                let _ = writeln!(out, "{phase},{},{mine},{speedup}", r.ranks);
            }
            let _ = writeln!(out, "total,{},{},{}", r.ranks, r.seconds, self.speedup(k));
            if let (Some(its), Some(speedup)) =
                (r.newton_iterations, self.speedup_per_newton_iteration(k))
            {
                let per = r.seconds / its as f64;
                let _ = writeln!(out, "per_newton_iteration,{},{per},{speedup}", r.ranks);
            }
        }
        out
    }

    /// Writes `scaling.csv` and `scaling.png`/`.svg` into `dir`; returns plot warnings.
    pub fn write(&self, dir: &Path) -> Result<Vec<String>> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        write_atomic(&dir.join("scaling.csv"), self.csv().as_bytes())?;
        let ranks = |k: usize| self.runs[k].ranks as f64;
        let n = self.runs.len();
        let mut series = vec![
            plot::Series {
                name: "total (wall)".into(),
                points: (0..n).map(|k| (ranks(k), self.runs[k].seconds)).collect(),
                ..Default::default()
            },
            plot::Series {
                name: "ideal".into(),
                points: (0..n)
                    .map(|k| (ranks(k), self.runs[0].seconds * ranks(0) / ranks(k)))
                    .collect(),
                ..Default::default()
            },
        ];
        for phase in PLOTTED {
            series.push(plot::Series {
                name: phase.into(),
                points: (0..n)
                    .map(|k| (ranks(k), self.phase_seconds(k, phase)))
                    .collect(),
                ..Default::default()
            });
        }
        let stem = dir.join("scaling");
        let title = format!(
            "Strong scaling: speedup {:.2} on {} ranks",
            self.speedup(n - 1),
            self.runs[n - 1].ranks
        );
        plot::Figure::new(&stem, &title, "ranks", "wall time (s)").loglog_points(&series)
    }
}

/// One row of the table: the name, the time of every run, the speedup of every run after the
/// first.
fn table_row(out: &mut String, name: &str, seconds: Vec<f64>) {
    let _ = write!(out, "{name:<20}");
    for s in &seconds {
        let _ = write!(out, "{s:>14.4}");
    }
    for s in &seconds[1..] {
        match ratio(seconds[0], *s) {
            Some(r) => write!(out, "{r:>14.2}"),
            None => write!(out, "{:>14}", "-"),
        }
        .unwrap_or(());
    }
    out.push('\n');
}

/// A speedup: `before / after`; `None` when `after` is not positive (a phase the run did
/// not have).
fn ratio(before: f64, after: f64) -> Option<f64> {
    (after > 0.0).then(|| before / after)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(ranks: usize, seconds: f64, stages: &[(&str, f64)]) -> PetscLog {
        PetscLog {
            ranks,
            seconds,
            stages: stages.iter().map(|(n, t)| (n.to_string(), *t)).collect(),
            newton_iterations: Some(4 * ranks),
        }
    }

    #[test]
    fn phases_sum_their_stages_and_speedups_divide() {
        let s = Scaling {
            runs: vec![
                run(
                    1,
                    10.0,
                    &[("Main Stage", 1.0), ("setup", 0.5), ("solve", 6.0)],
                ),
                run(
                    2,
                    5.0,
                    &[("Main Stage", 1.0), ("setup", 0.5), ("solve", 2.5)],
                ),
            ],
        };
        assert_eq!(s.phase_seconds(0, "start and setup"), 1.5);
        assert_eq!(s.phase_seconds(1, "linear solve"), 2.5);
        assert_eq!(s.phase_seconds(1, "mortar integration"), 0.0);
        assert_eq!(s.speedup(1), 2.0);
        let csv = s.csv();
        assert!(csv.contains("linear solve,2,2.5,2.4\n"), "{csv}");
        assert!(csv.contains("total,2,5,2\n"), "{csv}");
        // 10 s for 4 iterations on 1 rank, 5 s for 8 on 2: 2.5 s against 0.625 s.
        assert_eq!(s.speedup_per_newton_iteration(1), Some(4.0));
        assert!(csv.ends_with("per_newton_iteration,2,0.625,4\n"), "{csv}");
        let table = s.table();
        let total = table.lines().find(|l| l.starts_with("total")).unwrap();
        assert!(total.ends_with("2.00"), "{table}");
        assert!(table.lines().last().unwrap().ends_with("4.00"), "{table}");
        // A phase neither run had (a scene without contact): 0 s, no speedup, no NaN.
        assert!(csv.contains("mortar integration,2,0,\n"), "{csv}");
        let row = table.lines().find(|l| l.starts_with("mortar")).unwrap();
        assert!(row.ends_with(" -"), "{table}");
        assert!(!csv.to_lowercase().contains("nan") && !table.contains("NaN"));
    }

    #[test]
    fn logs_of_different_scenes_or_rank_orders_are_refused() {
        let stages = [
            ("Main Stage", 1.0),
            ("setup", 0.5),
            ("assembly", 2.0),
            ("solve", 6.0),
            ("output", 0.1),
        ];
        let check = |runs: Vec<PetscLog>| Scaling { runs }.check();
        assert_eq!(
            check(vec![run(1, 10.0, &stages), run(2, 6.0, &stages)]),
            Ok(())
        );
        assert_eq!(
            check(vec![
                run(1, 10.0, &stages),
                run(2, 6.0, &stages),
                run(4, 4.0, &stages)
            ]),
            Ok(())
        );
        // The same log twice, or the 2-rank run first.
        let (k, msg) = check(vec![run(2, 6.0, &stages), run(2, 6.0, &stages)]).unwrap_err();
        assert!(k == 1 && msg.contains("strictly increasing"), "{msg}");
        let (k, msg) = check(vec![run(2, 6.0, &stages), run(1, 10.0, &stages)]).unwrap_err();
        assert!(k == 1 && msg.contains("fewest ranks"), "{msg}");
        // Not a log of `mortar run`: only PETSc's own stage.
        let (k, msg) = check(vec![run(1, 10.0, &stages[..1]), run(2, 6.0, &stages)]).unwrap_err();
        assert!(k == 0 && msg.contains("'setup'"), "{msg}");
        // A contact scene against a scene without contact, either way round.
        let contact = [&stages[..], &[("Mortar integration", 3.0)]].concat();
        let (k, msg) = check(vec![run(1, 10.0, &contact), run(2, 6.0, &stages)]).unwrap_err();
        assert!(k == 1 && msg.contains("'Mortar integration'"), "{msg}");
        let (k, msg) = check(vec![run(1, 10.0, &stages), run(2, 6.0, &contact)]).unwrap_err();
        assert!(k == 1 && msg.contains("'Mortar integration'"), "{msg}");
        // Newton iterations in one log only.
        let mut bare = run(2, 6.0, &stages);
        bare.newton_iterations = None;
        let (k, msg) = check(vec![run(1, 10.0, &stages), bare]).unwrap_err();
        assert!(k == 1 && msg.contains("SNESJacobianEval"), "{msg}");
    }
}
