//! What a run wrote (`summary.json`, `displacement.csv`) and printed (`-snes_monitor`, its
//! error line).

use std::path::Path;
use std::process::Output;

/// summary.json as JSON.
pub fn summary(out_dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Newton iterations of every step of a run that must have converged.
pub fn converged_newton_its(out_dir: &Path) -> Vec<u64> {
    let s = summary(out_dir);
    assert_eq!(s["converged"], true, "{}", out_dir.display());
    s["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|st| st["newton_its"].as_u64().unwrap())
        .collect()
}

/// A metric from summary.json.
pub fn metric(out_dir: &Path, name: &str) -> f64 {
    summary(out_dir)["metrics"][name]
        .as_f64()
        .unwrap_or_else(|| panic!("no metric {name} in {}", out_dir.display()))
}

/// displacement.csv as rows of `[x, y, z, ux, uy, uz]`, by node.
pub fn displacements(out_dir: &Path) -> Vec<[f64; 6]> {
    let text = std::fs::read_to_string(out_dir.join("displacement.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').skip(1).map(|s| s.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3], v[4], v[5]]
        })
        .collect()
}

/// Largest displacement difference relative to the largest displacement.
pub fn max_rel_difference(a: &[[f64; 6]], b: &[[f64; 6]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a
        .iter()
        .flat_map(|r| r[3..].iter().map(|v| v.abs()))
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .flat_map(|(r, s)| (3..6).map(move |k| (r[k] - s[k]).abs()))
        .fold(0.0, f64::max);
    diff / scale
}

/// [`max_rel_difference`] of the displacements two runs wrote into `a` and `b`.
pub fn max_rel_difference_of_runs(a: &Path, b: &Path) -> f64 {
    max_rel_difference(&displacements(a), &displacements(b))
}

/// The residual norms printed by `-snes_monitor`, one list per solve.
pub fn snes_monitor_histories(stdout: &str) -> Vec<Vec<f64>> {
    let mut all: Vec<Vec<f64>> = Vec::new();
    for line in stdout.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() == 5 && t[1] == "SNES" && t[3] == "norm" {
            let k: usize = t[0].parse().unwrap();
            let r: f64 = t[4].parse().unwrap();
            if k == 0 {
                all.push(Vec::new());
            }
            all.last_mut().unwrap().push(r);
        }
    }
    all
}

/// history.csv of a run: its column names, and the column of `name` in its rows.
pub struct History {
    /// The column names (the first line).
    pub header: Vec<String>,
    /// The rows after it, as text.
    pub lines: Vec<String>,
}

impl History {
    /// Reads `history.csv` in `out_dir`.
    pub fn read(out_dir: &Path) -> History {
        let text = std::fs::read_to_string(out_dir.join("history.csv")).unwrap();
        let mut lines = text.lines().map(String::from);
        let header = lines.next().unwrap().split(',').map(String::from).collect();
        History {
            header,
            lines: lines.collect(),
        }
    }

    /// The position of column `name`.
    pub fn column(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// The rows, every field a number.
    pub fn rows(&self) -> Vec<Vec<f64>> {
        self.lines
            .iter()
            .map(|l| l.split(',').map(|s| s.parse().unwrap()).collect())
            .collect()
    }

    /// The sum of column `name` over the steps.
    pub fn sum(&self, name: &str) -> f64 {
        let k = self.column(name);
        self.rows().iter().map(|r| r[k]).sum()
    }
}

/// The one `mortar: error:` line of a failed run's stderr (mpirun adds its own banners around
/// it); `what` names the run in the messages. Fails unless the run failed without timing out
/// (mpirun's `--timeout` gives exit code 110) and printed exactly one such line.
pub fn the_error_line(out: &Output, what: &str) -> String {
    assert_ne!(out.status.code(), Some(0), "{what}");
    assert_ne!(out.status.code(), Some(110), "{what}: timed out");
    let lines: Vec<String> = String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| l.starts_with("mortar: error:"))
        .map(String::from)
        .collect();
    assert_eq!(lines.len(), 1, "{what}: {lines:?}");
    lines[0].clone()
}
