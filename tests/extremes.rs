//! Numerical stability at the extremes, in release mode: `cargo test --release --test extremes`
//! (the reduced set, in CI) or `ci/extremes` (the full set, `MORTAR_EXTREMES=full`).
//!
//! Every case is the small frictional slide of `common::slide_case` (Hex8, one element through
//! the thickness of each block, one pass, mu = 0.3, penalty 100 E/h) with one thing pushed to
//! an extreme: the penalty factor from 1 to 1e8, mu up to 1, a near-incompressible material
//! (nu = 0.49), the upper block pushed until its nodes slide off the lower surface, meshes
//! offset by 1e-9 (sliver overlaps), an initial penetration of half an element; the slide off
//! the edge and the slivers also with the overlaps split into fans of pallets.
//!
//! Each run must end converged or with one diagnosed error line after step cutting: never a
//! panic, never a NaN or an infinity in a result file (CSV, JSON, VTU). The cases marked
//! `must converge` are asserted to. A table goes to stdout: case, outcome (converged, cut steps,
//! diagnosed failure), Newton iterations (total and largest per step), the largest
//! penetration relative to h, and the NaN count.

mod common;

use std::path::Path;

/// One extreme: name, case text, whether it must converge.
type Extreme = (&'static str, String, bool);

fn extremes(full: bool) -> Vec<Extreme> {
    let base = common::slide_case(5);
    let with = |from: &str, to: &str| -> String {
        assert!(base.contains(from), "the edit {from:?} does not apply");
        base.replace(from, to)
    };
    let penalty = |p: &str| with("friction = 0.3", &format!("friction = 0.3\npenalty = {p}"));
    let blocks = "lo = [0.25, 0.1, 0.5]\nhi = [0.95, 0.9, 1.0]";
    let off_the_edge = with("value = [0.2]", "value = [1.0]").replace("count = 5", "count = 12");
    let slivers = with(
        blocks,
        "lo = [0.250000001, 0.100000001, 0.5]\nhi = [0.950000001, 0.900000001, 1.0]",
    );
    let mut cases: Vec<Extreme> = vec![
        (
            "base (one element through the thickness)",
            base.clone(),
            true,
        ),
        ("penalty 1e0 E/h", penalty("1.0"), true),
        ("penalty 1e8 E/h", penalty("1e8"), false),
        ("mu 1.0", with("friction = 0.3", "friction = 1.0"), true),
        (
            "nu 0.49",
            base.replace("poisson = 0.3", "poisson = 0.49"),
            true,
        ),
        ("slide off the edge", off_the_edge.clone(), true),
        ("offset 1e-9 (slivers)", slivers.clone(), true),
        (
            "penetration of half an element",
            with(blocks, "lo = [0.25, 0.1, 0.25]\nhi = [0.95, 0.9, 0.75]"),
            true,
        ),
        (
            "slide off the edge, fan pallets",
            common::with_fan_pallets(&off_the_edge),
            true,
        ),
        (
            "offset 1e-9 (slivers), fan pallets",
            common::with_fan_pallets(&slivers),
            true,
        ),
    ];
    if full {
        cases.extend([
            ("penalty 1e1 E/h", penalty("10.0"), true),
            ("penalty 1e3 E/h", penalty("1e3"), false),
            ("penalty 1e4 E/h", penalty("1e4"), false),
            ("penalty 1e5 E/h", penalty("1e5"), false),
            ("penalty 1e6 E/h", penalty("1e6"), false),
            ("penalty 1e7 E/h", penalty("1e7"), false),
            ("mu 0", with("friction = 0.3", "friction = 0.0"), true),
            ("mu 0.5", with("friction = 0.3", "friction = 0.5"), true),
            (
                "nu 0.49, mu 1.0",
                with("friction = 0.3", "friction = 1.0").replace("poisson = 0.3", "poisson = 0.49"),
                true,
            ),
            (
                "node-on-segment, slide off the edge",
                common::with_node_on_segment(&off_the_edge),
                false,
            ),
        ]);
    }
    cases
}

/// NaN and infinity tokens in the result files under `dir` (CSV, JSON, VTU, PVTU).
fn non_finite_count(dir: &Path) -> usize {
    let mut count = 0;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            count += non_finite_count(&path);
            continue;
        }
        let result = path
            .extension()
            .is_some_and(|e| ["csv", "json", "vtu", "pvtu"].iter().any(|x| e == *x));
        if result {
            let text = std::fs::read_to_string(&path)
                .unwrap_or_default()
                .to_lowercase();
            count += text
                .split(|c: char| !c.is_ascii_alphanumeric() && c != '.' && c != '-' && c != '+')
                .filter(|t| {
                    let t = t.trim_start_matches(['-', '+']);
                    t == "nan" || t == "inf" || t == "infinity"
                })
                .count();
        }
    }
    count
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test extremes"
)]
fn extremes_end_converged_or_diagnosed_without_nan() {
    let full = std::env::var("MORTAR_EXTREMES").is_ok_and(|v| v == "full");
    let mut table = vec![format!(
        "{:<40} {:>7} {:>8} {:>12} {:>4}  {}",
        "case", "newton", "max/step", "penetration", "NaN", "outcome"
    )];
    let mut problems = Vec::new();
    for (i, (name, case, must_converge)) in extremes(full).into_iter().enumerate() {
        let path = common::write_case(&format!("extreme_{i}"), &case);
        let out = path.parent().unwrap().join("out");
        let run = common::run_raw(&path, 1, &out, &["-q"]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        let errors: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("mortar: error:"))
            .collect();
        let nan = non_finite_count(&out);
        // A failure before the first step leaves no summary: its columns read "-".
        let summary: serde_json::Value = std::fs::read_to_string(out.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        let metric = |k: &str| summary["metrics"][k].as_f64();
        let cuts: u64 = summary["steps"]
            .as_array()
            .map_or(0, |s| s.iter().filter_map(|st| st["cut"].as_u64()).sum());
        let outcome = if run.status.success() {
            if cuts > 0 {
                format!("converged after {cuts} cut(s)")
            } else {
                "converged".to_string()
            }
        } else {
            let msg = errors.first().map_or("(no error line)", |l| {
                l.trim_start_matches("mortar: error: ")
            });
            format!("diagnosed failure: {msg}")
        };
        let penetration = summary["metrics"]
            .as_object()
            .and_then(|m| {
                m.iter()
                    .find(|(k, _)| k.starts_with("max_rel_penetration_"))
                    .and_then(|(_, v)| v.as_f64())
            })
            .map_or("-".to_string(), |p| format!("{p:.2e}"));
        table.push(format!(
            "{name:<40} {:>7} {:>8} {penetration:>12} {nan:>4}  {outcome}",
            metric("total_newton_its").map_or("-".into(), |v| format!("{v}")),
            metric("max_newton_its").map_or("-".into(), |v| format!("{v}")),
        ));
        if stderr.contains("panicked") {
            problems.push(format!("{name}: panic\n{stderr}"));
        }
        if !run.status.success() && errors.len() != 1 {
            problems.push(format!("{name}: not one error line\n{stderr}"));
        }
        if nan > 0 {
            problems.push(format!(
                "{name}: {nan} NaN or infinite value(s) in the outputs"
            ));
        }
        if must_converge && !run.status.success() {
            problems.push(format!("{name}: did not converge: {stderr}"));
        }
    }
    println!("{}", table.join("\n"));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
