//! What refinement costs: `mortar family RUN_DIR ... [--out DIR]`.
//!
//! Each `RUN_DIR` is the output folder of one `mortar run` (its `summary.json` and
//! `history.csv`): the levels of a refinement family (`cases/refinement`), on one or more rank
//! counts. The table gives, per run, the free dofs, the Newton iterations, the linear
//! iterations per Newton iteration, the seconds of each phase of `summary.json`'s timings, the
//! seconds per Newton iteration, the peak memory of the largest rank and the balance of the
//! contact work (the busiest rank's seconds in search, integration and contact assembly over
//! the ranks' mean). Then:
//!
//! - **fits**: between successive sizes on the same number of ranks, the exponent `p` of
//!   `cost ~ n^p` (`n` the free dofs): `p = ln(c2 / c1) / ln(n2 / n1)` for the seconds per Newton
//!   iteration, each phase's seconds, the Newton iterations and the linear iterations per
//!   Newton iteration, and the peak memory;
//! - **speedups**: for each size run on several rank counts, each phase's seconds on the fewest
//!   ranks over its seconds on each other count.
//!
//! `family.csv` in `DIR` (default `out/family`) holds the table.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::io::output::{write_atomic, Summary};

/// The phases of the table: a column title and the `summary.json` timings it sums.
const PHASES: [(&str, &[&str]); 8] = [
    ("setup", &["setup"]),
    ("search", &["contact_search"]),
    ("integration", &["contact_integration"]),
    ("contact asm", &["contact_assembly"]),
    ("bulk asm", &["bulk_assembly"]),
    ("linear solve", &["solve"]),
    ("pattern", &["pattern"]),
    ("output", &["output"]),
];

/// One run of the family.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The run's folder name.
    pub name: String,
    pub ranks: usize,
    pub dofs: f64,
    pub steps: usize,
    /// Every step converged and the full load was reached.
    pub converged: bool,
    pub newton: f64,
    pub linear: f64,
    /// Seconds per phase, in the order of the table's phases (`PHASES`).
    pub seconds: Vec<f64>,
    /// The peak resident memory of the largest rank, MB (`None`: not recorded).
    pub peak_mb: Option<f64>,
    /// The contact seconds of the busiest rank over the ranks' mean ([`contact_balance`];
    /// `None` on one rank or without contact work).
    pub contact_balance: Option<f64>,
}

impl Run {
    /// Reads a run's folder.
    pub fn read(dir: &Path) -> Result<Run> {
        let summary = Summary::read(&dir.join("summary.json"))?;
        let dofs = *summary.metrics.get("free_dofs").ok_or_else(|| {
            Error::Other(format!(
                "family: {}: summary.json has no free_dofs (not a finished run?)",
                dir.display()
            ))
        })?;
        let timing = |names: &[&str]| names.iter().filter_map(|n| summary.timings.get(*n)).sum();
        Ok(Run {
            name: dir
                .file_name()
                .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into()),
            ranks: summary.ranks,
            dofs,
            steps: summary.steps.len(),
            converged: summary.converged,
            newton: summary.steps.iter().map(|s| s.newton_its as f64).sum(),
            linear: linear_iterations(&dir.join("history.csv"))?,
            seconds: PHASES.iter().map(|(_, names)| timing(names)).collect(),
            peak_mb: summary.peak_memory_mb.iter().copied().reduce(f64::max),
            contact_balance: contact_balance(&summary.contact_seconds_per_rank),
        })
    }

    /// Seconds in all (the phases' sum).
    pub fn total(&self) -> f64 {
        self.seconds.iter().sum()
    }

    /// Seconds per Newton iteration (in all, when the run took none).
    pub fn per_newton(&self) -> f64 {
        self.total() / self.newton.max(1.0)
    }

    /// Linear iterations per Newton iteration.
    pub fn linear_per_newton(&self) -> f64 {
        self.linear / self.newton.max(1.0)
    }
}

/// The largest of the ranks' contact seconds over their mean: 1 when the contact work is dealt
/// out evenly; `None` for fewer than two ranks or no contact work.
fn contact_balance(per_rank: &[f64]) -> Option<f64> {
    let mean = per_rank.iter().sum::<f64>() / per_rank.len() as f64;
    let max = per_rank.iter().copied().fold(0.0, f64::max);
    (per_rank.len() > 1 && mean > 0.0).then(|| max / mean)
}

/// The sum of the `linear_its` column of a `history.csv`.
fn linear_iterations(path: &Path) -> Result<f64> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    let column = header
        .split(',')
        .position(|c| c == "linear_its")
        .ok_or_else(|| Error::Other(format!("family: {}: no linear_its column", path.display())))?;
    let mut sum = 0.0;
    for line in lines {
        let value = line
            .split(',')
            .nth(column)
            .and_then(|v| v.parse::<f64>().ok());
        sum += value
            .ok_or_else(|| Error::Other(format!("family: {}: bad row '{line}'", path.display())))?;
    }
    Ok(sum)
}

/// The runs of a family, ordered by ranks, then size.
#[derive(Clone, Debug)]
pub struct Family {
    pub runs: Vec<Run>,
}

impl Family {
    /// Reads the runs' folders.
    pub fn read(dirs: &[PathBuf]) -> Result<Family> {
        let mut runs = dirs
            .iter()
            .map(|d| Run::read(d))
            .collect::<Result<Vec<_>>>()?;
        runs.sort_by(|a, b| a.ranks.cmp(&b.ranks).then(a.dofs.total_cmp(&b.dofs)));
        Ok(Family { runs })
    }

    /// The table, the fits and the speedups, as printed.
    pub fn report(&self) -> String {
        let mut out = self.table();
        out.push_str(&self.fits());
        out.push_str(&self.speedups());
        out
    }

    /// One row per run.
    fn table(&self) -> String {
        let mut out = format!(
            "{:<18} {:>5} {:>9} {:>6} {:>7} {:>8}",
            "run", "ranks", "dofs", "steps", "newton", "lin/nwt"
        );
        for (title, _) in PHASES {
            let _ = write!(out, " {title:>12}");
        }
        let _ = writeln!(
            out,
            " {:>9} {:>9} {:>8} {:>8}",
            "total s", "s/newton", "peak MB", "contact"
        );
        for r in &self.runs {
            let _ = write!(
                out,
                "{:<18} {:>5} {:>9.0} {:>6} {:>7.0} {:>8.1}",
                r.name,
                r.ranks,
                r.dofs,
                format!("{}{}", r.steps, if r.converged { "" } else { "!" }),
                r.newton,
                r.linear_per_newton()
            );
            for s in &r.seconds {
                let _ = write!(out, " {s:>12.2}");
            }
            let peak = r.peak_mb.map_or("-".to_string(), |m| format!("{m:.0}"));
            let balance = r.contact_balance.map_or("-".into(), |b| format!("{b:.3}"));
            let _ = writeln!(
                out,
                " {:>9.2} {:>9.4} {peak:>8} {balance:>8}",
                r.total(),
                r.per_newton()
            );
        }
        out
    }

    /// The exponents between successive sizes on the same number of ranks (module docs).
    fn fits(&self) -> String {
        let mut out = String::new();
        for pair in self.runs.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            if a.ranks != b.ranks || b.dofs <= a.dofs {
                continue;
            }
            let p = |ca: f64, cb: f64| exponent(a.dofs, b.dofs, ca, cb);
            let _ = write!(
                out,
                "fit {} -> {} ({} rank(s)): s/newton n^{}, newton n^{}, lin/nwt n^{}",
                a.name,
                b.name,
                a.ranks,
                p(a.per_newton(), b.per_newton()),
                p(a.newton, b.newton),
                p(a.linear_per_newton(), b.linear_per_newton())
            );
            for (k, (title, _)) in PHASES.iter().enumerate() {
                let _ = write!(out, ", {title} n^{}", p(a.seconds[k], b.seconds[k]));
            }
            if let (Some(ma), Some(mb)) = (a.peak_mb, b.peak_mb) {
                let _ = write!(out, ", memory n^{}", p(ma, mb));
            }
            out.push('\n');
        }
        out
    }

    /// Each phase's speedup from the fewest ranks of a size to each other count.
    fn speedups(&self) -> String {
        let mut out = String::new();
        for base in &self.runs {
            for other in self.runs.iter().filter(|r| {
                r.dofs == base.dofs
                    && r.ranks > base.ranks
                    && !self
                        .runs
                        .iter()
                        .any(|f| f.dofs == base.dofs && f.ranks < base.ranks)
            }) {
                let _ = write!(
                    out,
                    "speedup {} ({} -> {} ranks): total {:.2}, s/newton {:.2}",
                    base.name,
                    base.ranks,
                    other.ranks,
                    base.total() / other.total(),
                    base.per_newton() / other.per_newton()
                );
                for (k, (title, _)) in PHASES.iter().enumerate() {
                    match ratio(base.seconds[k], other.seconds[k]) {
                        Some(s) => {
                            let _ = write!(out, ", {title} {s:.2}");
                        }
                        None => {
                            let _ = write!(out, ", {title} -");
                        }
                    }
                }
                out.push('\n');
            }
        }
        out
    }

    /// `family.csv`: one row per run.
    pub fn csv(&self) -> String {
        let mut out = String::from("run,ranks,dofs,steps,converged,newton_its,linear_its");
        for (title, _) in PHASES {
            let _ = write!(out, ",seconds_{}", title.replace(' ', "_"));
        }
        out.push_str(",seconds_total,seconds_per_newton,peak_memory_mb,contact_balance\n");
        for r in &self.runs {
            let _ = write!(
                out,
                "{},{},{},{},{},{},{}",
                r.name, r.ranks, r.dofs, r.steps, r.converged as u8, r.newton, r.linear
            );
            for s in &r.seconds {
                let _ = write!(out, ",{s}");
            }
            let peak = r.peak_mb.map_or(String::new(), |m| m.to_string());
            let balance = r.contact_balance.map_or(String::new(), |b| b.to_string());
            let _ = writeln!(out, ",{},{},{peak},{balance}", r.total(), r.per_newton());
        }
        out
    }

    /// Writes `family.csv` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let path = dir.join("family.csv");
        write_atomic(&path, self.csv().as_bytes())?;
        Ok(path)
    }
}

/// The exponent `p` of `c ~ n^p` through two points, to two decimals (`-` where a cost is 0).
fn exponent(n1: f64, n2: f64, c1: f64, c2: f64) -> String {
    if c1 > 0.0 && c2 > 0.0 && n2 > n1 {
        format!("{:.2}", (c2 / c1).ln() / (n2 / n1).ln())
    } else {
        "-".into()
    }
}

/// `before / after`, where both are positive.
fn ratio(before: f64, after: f64) -> Option<f64> {
    (before > 0.0 && after > 0.0).then(|| before / after)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(name: &str, ranks: usize, dofs: f64, newton: f64, seconds: f64) -> Run {
        Run {
            name: name.into(),
            ranks,
            dofs,
            steps: 20,
            converged: true,
            newton,
            linear: 10.0 * newton,
            seconds: vec![seconds / PHASES.len() as f64; PHASES.len()],
            peak_mb: Some(dofs / 100.0),
            contact_balance: (ranks > 1).then_some(1.05),
        }
    }

    /// Costs that grow like `n^1.5` (time per Newton iteration), `n^0` (iterations) and `n^1`
    /// (memory) give those exponents; two rank counts of a size give their ratio.
    #[test]
    fn fits_and_speedups_read_the_powers_and_ratios() {
        let (n1, n2) = (1e4, 8e4);
        let family = Family {
            runs: vec![
                run("a", 1, n1, 100.0, 10.0),
                run("b", 1, n2, 100.0, 10.0 * 8f64.powf(1.5)),
                run("a2", 2, n1, 100.0, 5.5),
            ],
        };
        let fits = family.fits();
        assert!(fits.contains("s/newton n^1.50"), "{fits}");
        assert!(fits.contains("newton n^0.00"), "{fits}");
        assert!(fits.contains("memory n^1.00"), "{fits}");
        assert_eq!(fits.lines().count(), 1, "no fit across rank counts: {fits}");
        let speedups = family.speedups();
        assert!(
            speedups.contains("speedup a (1 -> 2 ranks): total 1.82"),
            "{speedups}"
        );
        assert_eq!(speedups.lines().count(), 1, "{speedups}");
        assert_eq!(family.csv().lines().count(), 4);
    }

    /// The busiest rank over the mean; nothing to balance on one rank or without contact.
    #[test]
    fn contact_balance_is_the_busiest_rank_over_the_mean() {
        assert_eq!(contact_balance(&[3.0, 1.0]), Some(1.5));
        assert_eq!(contact_balance(&[2.0, 2.0, 2.0]), Some(1.0));
        assert_eq!(contact_balance(&[4.0]), None);
        assert_eq!(contact_balance(&[0.0, 0.0]), None);
        assert_eq!(contact_balance(&[]), None);
        let family = Family {
            runs: vec![run("a2", 2, 1e4, 100.0, 5.5)],
        };
        assert!(family.table().lines().nth(1).unwrap().ends_with(" 1.050"));
        assert!(family.csv().lines().nth(1).unwrap().ends_with(",1.05"));
    }

    #[test]
    fn linear_iterations_sum_their_column() {
        let dir = std::env::temp_dir().join(format!("mortar-family-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("history.csv");
        std::fs::write(&path, "step,load,linear_its\n1,0.5,7\n2,1,11\n").unwrap();
        assert_eq!(linear_iterations(&path).unwrap(), 18.0);
        std::fs::write(&path, "step,load\n1,0.5\n").unwrap();
        assert!(linear_iterations(&path).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
