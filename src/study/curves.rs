//! Comparing load curves between variants (`[curves]`).
//!
//! The runs at the **last** refinement level are compared: each variant's `history.csv` (one
//! row per converged load step) gives the points `(x, y)` of its curve (`(x, |y|)` with `abs`),
//! in load order. For every variant other than the reference, the metric
//! `curve_max_rel_diff_<variant>` (or `<curves.metric>_<variant>`) is the largest, over the
//! reference's points with `x > after`, of `|y_v(x) - y_ref(x)| / |y_ref(x)|`, where `y_v` is
//! the variant's curve linearly interpolated at the reference's `x` (its points sorted by x; of
//! several points at one x, the last in load order). Reference points outside the variant's x
//! range, and those with `y_ref = 0`, are skipped; when none is left there is no metric. A run
//! that failed or diverged is still plotted with the points it has (its converged steps) and
//! compared over the overlap; one that failed before its first step has no points. Steps
//! accepted without convergence (`steps.on_failure = "continue"`: `converged` = 0 in the
//! history) are ringed on the plot, and the legend gives their number and, for a run that
//! stopped early, the x where it stopped. Every variant also gets `smoothness_<variant>`: the
//! largest change of y between consecutive points with `x > after` over the mean change (about
//! 1-2 for a smooth curve of even steps; a spike k times the typical step gives about k). The
//! column names are checked against the first run's `history.csv`, so a misspelt one stops the
//! study after one run.
//!
//! Outputs: `curves.png`, `curves.svg`, y against x on linear axes, one line per variant (its
//! run at the last level), `title` as the title ([`plot::Figure::lines`]); the metrics above
//! in the study summary, added once every run is done; and the Pareto front of the curves'
//! difference to the reference against wall time ([`crate::study::pareto`]: with no exact
//! solution, the reference variant is the truth, and is not on the plot).

use std::path::Path;

use mpi::collective::Root;
use mpi::topology::Communicator;

use super::file::{CurvesSpec, Study};
use super::output::{study_csv, RunRecord};
use crate::error::{print_warning, Error, Result};
use crate::io::output::{read_csv, write_atomic, Summary};
use crate::io::plot;
use crate::petsc::Petsc;

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

impl Curves {
    /// The `[curves]` table `c` with its defaults resolved: the study's `title`, or
    /// `<scene name>: <y label>`.
    pub(super) fn new(c: CurvesSpec, title: Option<&str>, scene_name: &str) -> Curves {
        let y_label = c.y_label.unwrap_or_else(|| {
            if c.abs {
                format!("|{}|", c.y)
            } else {
                c.y.clone()
            }
        });
        Curves {
            x_label: c.x_label.unwrap_or_else(|| c.x.clone()),
            title: title.map_or_else(|| format!("{scene_name}: {y_label}"), str::to_string),
            y_label,
            x: c.x,
            y: c.y,
            reference: c.reference,
            after: c.after.unwrap_or(f64::NEG_INFINITY),
            abs: c.abs,
            metric: c.metric.unwrap_or_else(|| "curve_max_rel_diff".to_string()),
        }
    }
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

impl CurveFigures {
    /// Puts the figures into the study summary: `<curves.metric>_<variant>` and
    /// `smoothness_<variant>`.
    fn add_to(&self, curves: &Curves, summary: &mut Summary) {
        for (name, d) in &self.differences {
            if let Some(d) = d {
                summary
                    .metrics
                    .insert(format!("{}_{name}", curves.metric), *d);
            }
        }
        for (name, s) in &self.smoothness {
            if let Some(s) = s {
                summary.metrics.insert(format!("smoothness_{name}"), *s);
            }
        }
    }

    /// The progress note of the differences.
    fn note(&self, curves: &Curves) -> String {
        let diffs: Vec<String> = self
            .differences
            .iter()
            .map(|(name, d)| match d {
                Some(d) => format!("{name} {d:.3e}"),
                None => format!("{name} (none)"),
            })
            .collect();
        format!(
            "curves: largest relative difference to {}: {}",
            curves.reference,
            if diffs.is_empty() {
                "(no other variant)".to_string()
            } else {
                diffs.join(", ")
            }
        )
    }
}

impl Study {
    /// Checks the `[curves]` columns against the `history.csv` in `run_dir` (rank 0), and
    /// shares the verdict with every rank: false if there is no history yet (the run failed
    /// before its first step), true if the columns are there; an error on every rank (naming the
    /// study file, the key and the column on rank 0) if one is missing.
    pub(super) fn check_columns(&self, petsc: &Petsc, run_dir: &Path) -> Result<bool> {
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

    /// The curves' outputs, once every run is done (rank 0): `curves.png`/`.svg`, the Pareto
    /// front of the curves' differences against wall time (its flags set on `runs`), `study.csv`
    /// and the summary's curve metrics. Returns the progress notes.
    pub(super) fn write_curve_outputs(
        &self,
        curves: &Curves,
        runs: &mut [RunRecord],
        summary: &mut Summary,
        out: &Path,
    ) -> Result<[String; 2]> {
        let figures = self.write_curves(curves, out)?;
        // The Pareto front of the curves' difference to the reference against time.
        let mut scored = curve_scores(runs, curves, &figures, self.refinements.len() - 1);
        for i in self.front(&scored) {
            runs[i].on_front = true;
            scored[i].on_front = true;
        }
        let label = format!("{} to {}", curves.metric, curves.reference);
        let front = self.write_pareto(&scored, &label, summary, out)?;
        write_atomic(&out.join("study.csv"), study_csv(runs).as_bytes())?;
        figures.add_to(curves, summary);
        summary.write(&out.join("summary.json"))?;
        Ok([front, figures.note(curves)])
    }

    /// Reads every variant's curve at the last level, writes `curves.png` and `curves.svg`
    /// (rank 0), and returns, in variant order, the largest relative difference of every
    /// variant but the reference to the reference and every variant's smoothness figure (see
    /// the module docs).
    fn write_curves(&self, curves: &Curves, out: &Path) -> Result<CurveFigures> {
        let level = self.refinements.len() - 1;
        let series = self
            .variants
            .iter()
            .map(|v| {
                let run_dir = out.join("runs").join(&v.name).join(level.to_string());
                self.curve_of(curves, &v.name, &run_dir)
            })
            .collect::<Result<Vec<plot::Series>>>()?;
        let stem = out.join("curves");
        let figure = plot::Figure::new(&stem, &curves.title, &curves.x_label, &curves.y_label);
        plot::print_warnings(figure.lines(&series)?);
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

    /// The curve of variant `name` from the `history.csv` in its `run_dir` (none, with a
    /// warning, when there is no history), its unconverged steps flagged, its legend entry
    /// saying how it ended.
    fn curve_of(&self, curves: &Curves, name: &str, run_dir: &Path) -> Result<plot::Series> {
        let history = run_dir.join("history.csv");
        let (points, flagged) = if history.is_file() {
            let (columns, rows) = read_csv(&history)?;
            let (ix, iy) = curves
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
                "curves: variant '{name}' has no {} (no converged step): no curve",
                history.display()
            ));
            (Vec::new(), Vec::new())
        };
        let stopped = Summary::read(&run_dir.join("summary.json"))
            .map(|s| !s.completed)
            .unwrap_or(true);
        Ok(plot::Series {
            name: curve_legend(name, &points, &flagged, stopped),
            points,
            flagged,
        })
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
