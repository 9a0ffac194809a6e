//! `mortar study`: a small convergence study of the thick sphere (Hex8 and Hex20, n = 2, 3; small
//! enough for a debug build), a study with an impossible path, a study with failing runs,
//! `[curves]` studies of a one-element block (reaction against prescribed displacement), a sweep
//! on one mesh whose expectations bound each run's metrics, and the contact patch's shipped
//! study run from its file.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

use mortar::io::plot::fitted_slope;

/// A fresh folder with a copy of the thick-sphere case and `study.toml` = `study`.
fn study_dir(name: &str, study: &str) -> PathBuf {
    let dir = common::fresh_dir(name);
    let case = common::scene_dir("thick_sphere");
    for f in ["case.toml", "petscrc"] {
        std::fs::copy(case.join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("study.toml"), study).unwrap();
    dir
}

/// Runs `mortar study DIR/study.toml --out DIR/out ARGS` on one rank.
fn run_study(dir: &Path, args: &[&str]) -> Output {
    common::mortar_command()
        .arg("study")
        .arg(dir.join("study.toml"))
        .args(args)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("cannot start mortar")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The one line a failed study printed: it must have failed, with exactly one line on stderr,
/// `mortar: error: ...`.
fn one_error_line(o: &Output) -> String {
    let stderr = text(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].starts_with("mortar: error: "), "{stderr}");
    lines[0].to_string()
}

/// Refinements n = 2, 3 (h = 1/n) and the given variants.
fn small_study(variants: &str) -> String {
    format!(
        r#"
case = "case.toml"
metric = "energy_error"
title = "Thick sphere (test)"

[[refinement]]
h = 0.5
set = {{ "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2 }}

[[refinement]]
h = 0.3333333333333333
set = {{ "mesh.0.n_circ" = 3, "mesh.0.n_rad" = 3 }}
{variants}
"#
    )
}

/// study.csv as rows, each a map from column name to field; the header is checked.
fn csv_rows(out: &Path) -> Vec<BTreeMap<String, String>> {
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert_eq!(
        header,
        "variant,level,h,ranks,error,seconds,seconds_slowest,newton_its,converged,augmentations,\
         peak_memory_mb,on_front"
    );
    let names: Vec<&str> = header.split(',').collect();
    lines
        .map(|l| {
            names
                .iter()
                .map(|n| n.to_string())
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[test]
fn fitted_slope_recovers_a_power_law() {
    let pts: Vec<(f64, f64)> = [1.0, 0.5, 1.0 / 3.0, 0.25]
        .iter()
        .map(|&h: &f64| (h, 0.7 * h.powf(2.5)))
        .collect();
    assert!((fitted_slope(&pts) - 2.5).abs() < 1e-12);
}

#[test]
fn thick_sphere_study_writes_table_plot_and_slopes() {
    let dir = study_dir(
        "study_thick_sphere",
        &small_study(
            r#"
[[variant]]
name = "hex8"
set = { "mesh.0.element" = "hex8" }

[[variant]]
name = "hex20"
set = { "mesh.0.element" = "hex20" }
"#,
        ),
    );
    let o = run_study(&dir, &[]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(
        stdout.contains("hex20 level 1 h 0.3333: energy_error"),
        "{stdout}"
    );
    let out = dir.join("out");

    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 4, "{rows:?}");
    for (row, (variant, level)) in
        rows.iter()
            .zip([("hex8", "0"), ("hex8", "1"), ("hex20", "0"), ("hex20", "1")])
    {
        assert_eq!(
            (row["variant"].as_str(), row["level"].as_str()),
            (variant, level)
        );
        assert!(row["error"].parse::<f64>().unwrap() > 0.0, "{row:?}");
        assert_eq!(row["converged"], "true");
    }
    for (v, l) in [("hex8", 0), ("hex8", 1), ("hex20", 0), ("hex20", 1)] {
        let run = out.join(format!("runs/{v}/{l}"));
        assert!(run.join("summary.json").is_file(), "{}", run.display());
    }

    let png = std::fs::read(out.join("convergence.png")).unwrap();
    assert!(png.len() > 1000 && png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let svg = std::fs::read_to_string(out.join("convergence.svg")).unwrap();
    assert!(svg.contains("<svg"));

    let s = common::summary(&out);
    // The study's name is its folder's and its stem's.
    assert_eq!(s["case"], "study_thick_sphere_study");
    assert_eq!(s["converged"], true);
    assert!(s["message"].is_null());
    let metric = |k: &str| {
        s["metrics"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("no {k} in {s}"))
    };
    let (s8, s20) = (metric("slope_hex8"), metric("slope_hex20"));
    eprintln!("slopes: hex8 {s8:.3}, hex20 {s20:.3}");
    assert!(s20 > s8 && s8 > 0.5, "hex8 {s8}, hex20 {s20}");
    let e = metric("error_hex20_1");
    assert_eq!(e, rows[3]["error"].parse::<f64>().unwrap());
    // The slope is the one of the table's points.
    let pts: Vec<(f64, f64)> = rows[..2]
        .iter()
        .map(|r| (r["h"].parse().unwrap(), r["error"].parse().unwrap()))
        .collect();
    assert!((fitted_slope(&pts) - s8).abs() < 1e-12);

    // The Pareto front of error against wall time: no run on it is beaten in both by another
    // run, every run off it is; the plot exists; peak memory is recorded.
    let pts: Vec<(f64, f64, bool)> = rows
        .iter()
        .map(|r| {
            (
                r["seconds"].parse().unwrap(),
                r["error"].parse().unwrap(),
                r["on_front"] == "true",
            )
        })
        .collect();
    let beaten = |i: usize| {
        let (t, e, _) = pts[i];
        pts.iter()
            .enumerate()
            .any(|(j, &(tj, ej, _))| j != i && tj <= t && ej <= e && (tj < t || ej < e))
    };
    for (i, p) in pts.iter().enumerate() {
        assert_eq!(p.2, !beaten(i), "run {i}: {rows:?}");
        assert_eq!(
            metric(&format!(
                "on_front_{}_{}",
                rows[i]["variant"], rows[i]["level"]
            )),
            f64::from(u8::from(p.2))
        );
    }
    assert!(pts.iter().any(|p| p.2));
    assert!(
        rows.iter()
            .all(|r| r["peak_memory_mb"].parse::<f64>().unwrap() > 1.0),
        "{rows:?}"
    );
    assert!(out.join("pareto.png").is_file() && out.join("pareto.svg").is_file());
    assert!(
        stdout.contains("Pareto front of energy_error against wall time"),
        "{stdout}"
    );
}

/// `repeat = 3`: every run is made three times; `seconds` is the fastest and `seconds_slowest`
/// the slowest (times to the nanosecond: never equal for runs of their own), the outputs in
/// `runs/` are the first run's, and the repeats' scratch folders are gone.
#[test]
fn repeated_runs_keep_the_fastest_time() {
    let study = format!(
        "repeat = 3\n{}",
        small_study("[[variant]]\nname = \"hex8\"\nset = { \"mesh.0.element\" = \"hex8\" }\n")
    );
    let dir = study_dir("study_repeat_runs", &study);
    let o = run_study(&dir, &["-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.join("out");
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 2, "{rows:?}");
    for (level, r) in rows.iter().enumerate() {
        let (fastest, slowest): (f64, f64) = (
            r["seconds"].parse().unwrap(),
            r["seconds_slowest"].parse().unwrap(),
        );
        assert!(0.0 < fastest && fastest < slowest, "{r:?}");
        let run = out.join("runs/hex8").join(level.to_string());
        assert!(run.join("summary.json").is_file(), "{}", run.display());
        assert!(!run.with_extension("repeat").exists(), "{}", run.display());
    }
}

/// Peak memory is each run's own: a small run after a large one (the second variant's coarse
/// run after the first's fine one) reads its own peak, not the memory the large run freed.
#[test]
fn peak_memory_is_each_runs_own() {
    let study = r#"
case = "case.toml"
metric = "energy_error"

[[refinement]]
h = 0.5
set = { "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2 }

[[refinement]]
h = 0.2
set = { "mesh.0.n_circ" = 5, "mesh.0.n_rad" = 5 }

[[variant]]
name = "first"
set = { "mesh.0.element" = "hex27" }

[[variant]]
name = "second"
set = { "mesh.0.element" = "hex27" }
"#;
    let dir = study_dir("study_peak_memory", study);
    let o = run_study(&dir, &["-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rows = csv_rows(&dir.join("out"));
    let peak = |i: usize| rows[i]["peak_memory_mb"].parse::<f64>().unwrap();
    let (coarse, fine, coarse_after_fine) = (peak(0), peak(1), peak(2));
    assert!(fine > 2.0 * coarse, "{rows:?}");
    assert!(coarse_after_fine < 1.5 * coarse, "{rows:?}");
}

#[test]
fn unknown_path_fails_with_one_line_naming_it() {
    let dir = study_dir(
        "study_unknown_path",
        &small_study(
            r#"
[[variant]]
name = "hex8"
set = { "mesh.3.element" = "hex8" }
"#,
        ),
    );
    let line = one_error_line(&run_study(&dir, &["-q"]));
    assert!(line.contains("variant[0].set.\"mesh.3.element\""), "{line}");
    assert!(line.contains("study.toml"), "{line}");
    assert!(!dir.join("out").exists(), "nothing runs before validation");

    // A key the case does not know is created, and the case parser refuses it.
    let study = small_study(
        r#"
[[variant]]
name = "hex8"
set = { "mesh.0.elemnt" = "hex8" }
"#,
    );
    std::fs::write(dir.join("study.toml"), study).unwrap();
    let line = one_error_line(&run_study(&dir, &["-q"]));
    assert!(
        line.contains("elemnt") && line.contains("variant 'hex8'"),
        "{line}"
    );
}

#[test]
fn failed_runs_are_recorded_and_the_study_goes_on() {
    // "stuck": a finite-strain material, one Newton iteration allowed, a tolerance no
    // iteration meets, no cuts (with the linear material one iteration would reach the
    // round-off floor, which counts as converged). The expectations are still checked and
    // printed, on what the runs that converged measured.
    let dir = study_dir(
        "study_failed_runs",
        &small_study(
            r#"
[[variant]]
name = "stuck"
set = { "mesh.0.element" = "hex8", "material.0.model" = "neo_hookean", "newton.max_it" = 1, "newton.rtol" = 1e-30, "newton.atol" = 1e-40, "steps.predictor" = false, "steps.max_cuts" = 0 }

[[variant]]
name = "hex8"
set = { "mesh.0.element" = "hex8" }
"#,
        )
        .replace(
            "title = ",
            "expect = [\"slope_hex8 >= 0.5\", \"slope_stuck >= 0.5\"]\ntitle = ",
        ),
    );
    let o = run_study(&dir, &["-q"]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{stdout}");
    // -q: only the expectations.
    let printed: Vec<&str> = stdout.lines().collect();
    assert_eq!(printed.len(), 2, "{stdout}");
    assert!(
        printed[0].contains("expect slope_hex8 >= 0.5: slope_hex8 = ")
            && printed[0].ends_with("-> ok")
    );
    assert!(
        printed[1].ends_with("expect slope_stuck >= 0.5: no such metric -> FAILED"),
        "{stdout}"
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with("mortar: error: ") && lines[0].contains("2 of 4 runs failed"),
        "{stderr}"
    );
    let out = dir.join("out");
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 4, "{rows:?}");
    for r in &rows {
        let stuck = r["variant"] == "stuck";
        assert_eq!(
            r["converged"],
            if stuck { "false" } else { "true" },
            "{r:?}"
        );
        assert_eq!(r["error"].is_empty(), stuck, "{r:?}");
    }
    let s = common::summary(&out);
    assert_eq!(s["converged"], false);
    assert!(s["metrics"]["slope_hex8"].as_f64().unwrap() > 0.5);
    assert!(s["metrics"].get("slope_stuck").is_none());
    assert_eq!(s["metrics"]["failed_runs"].as_f64(), Some(2.0));
    assert!(s["message"].as_str().unwrap().contains("stuck level 0"));
    assert!(out.join("convergence.png").is_file() && out.join("convergence.svg").is_file());
}

/// A factorization package PETSc does not have: found when each run sets up its solver (not
/// inside a solve, where it would end the study), so both runs of the variant are recorded as
/// failed, and the one error line names the variant, the level and the package.
#[test]
fn a_missing_solver_package_fails_the_variants_runs() {
    let dir = study_dir(
        "study_solver_package",
        &small_study(
            r#"
[[variant]]
name = "no_such_package"
petsc = "-pc_type lu -pc_factor_mat_solver_type nonexistent"
"#,
        ),
    );
    let line = one_error_line(&run_study(&dir, &["-q"]));
    assert!(
        line.contains("2 of 2 runs failed")
            && line.contains("no_such_package level 0")
            && line.contains("solver type nonexistent"),
        "{line}"
    );
}

/// A fresh folder with `case.toml` = a one-element Neo-Hookean block (E = 100, nu = 0.3)
/// compressed along z by 0.2 in 4 steps, free to expand sideways, and `study.toml` = `study`.
/// The deformation is homogeneous, so the reaction is exactly proportional to E.
fn block_study_dir(name: &str, study: &str) -> PathBuf {
    let dir = common::fresh_dir(name);
    let case = common::compressed_block("hex8", 0.2, 4)
        .replace("divisions = [3, 3, 3]", "divisions = [1, 1, 1]");
    assert!(case.contains("divisions = [1, 1, 1]"));
    std::fs::write(dir.join("case.toml"), case).unwrap();
    std::fs::write(dir.join("study.toml"), study).unwrap();
    dir
}

/// A study of the block: `metric`, the given refinements, variants `soft` (the base case, the
/// reference) and `stiff` (E doubled) and more, and `[curves]` of the reaction on the top face
/// against its prescribed displacement (both negative; compared as |reaction|), plus `curves`.
fn block_study(refinements: &str, variants: &str, curves: &str) -> String {
    format!(
        r#"
case = "case.toml"
metric = "total_newton_its"
title = "Block (test)"
{refinements}

[[variant]]
name = "soft"

[[variant]]
name = "stiff"
set = {{ "material.0.young" = 200.0 }}
{variants}

[curves]
x = "u_b.zmax_z"
y = "reaction_b.zmax_z"
reference = "soft"
abs = true
{curves}
"#
    )
}

const ONE_REFINEMENT: &str = "[[refinement]]\nh = 1.0\n";

/// Two levels of the block: 2 load steps, then 4.
const TWO_REFINEMENTS: &str = r#"
[[refinement]]
h = 1.0
set = { "steps.count" = 2 }

[[refinement]]
h = 0.5
set = { "steps.count" = 4 }
"#;

/// `curve_max_rel_diff_<variant>` from the study summary.
fn curve_diff(out: &Path, variant: &str) -> Option<f64> {
    common::summary(out)["metrics"][format!("curve_max_rel_diff_{variant}")].as_f64()
}

/// Markers of the first series (circles) in an SVG plot, less the legend's.
fn first_series_markers(svg: &str) -> usize {
    let legend = usize::from(svg.contains("<text"));
    svg.matches("<circle").count() - legend
}

#[test]
fn curves_compare_variants_at_the_last_level() {
    // Level 0 in 2 steps, level 1 in 4: the curves are those of level 1.
    let refinements = TWO_REFINEMENTS;
    let dir = block_study_dir(
        "study_curves",
        &block_study(refinements, "", "x_label = \"top displacement\""),
    );
    let o = run_study(&dir, &[]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(
        stdout.contains("curves: largest relative difference to soft: stiff 1.000e0"),
        "{stdout}"
    );
    let out = dir.join("out");
    assert_eq!(csv_rows(&out).len(), 4);

    let png = std::fs::read(out.join("curves.png")).unwrap();
    assert!(png.len() > 1000 && png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let svg = std::fs::read_to_string(out.join("curves.svg")).unwrap();
    assert!(svg.contains("<svg"));
    assert_eq!(first_series_markers(&svg), 4, "the 4 steps of level 1");
    if svg.contains("<text") {
        for label in ["Block (test)", "top displacement", "|reaction_b.zmax_z|"] {
            assert!(svg.contains(&format!("\n{label}\n")), "no {label}");
        }
        // abs: the compressive (negative) reaction is plotted positive, up to 48.
        assert!(svg.contains("\n40\n") && !svg.contains("\n-40\n"));
    }
    // Two refinements: the convergence plot and the slopes too.
    assert!(out.join("convergence.png").is_file() && out.join("convergence.svg").is_file());
    let s = common::summary(&out);
    assert_eq!(s["converged"], true);
    assert!(s["metrics"]["slope_soft"].as_f64().is_some(), "{s}");

    // E doubled: the reaction doubles at every prescribed displacement.
    let d = curve_diff(&out, "stiff").expect("curve_max_rel_diff_stiff");
    assert!((d - 1.0).abs() < 1e-9, "{d}");
    assert_eq!(
        curve_diff(&out, "soft"),
        None,
        "the reference has no metric"
    );
    // The same from the runs' own histories.
    let last = |v: &str| {
        let h = std::fs::read_to_string(out.join(format!("runs/{v}/1/history.csv"))).unwrap();
        let mut lines = h.lines();
        let cols: Vec<&str> = lines.next().unwrap().split(',').collect();
        let k = cols.iter().position(|&c| c == "reaction_b.zmax_z").unwrap();
        let rows: Vec<f64> = lines
            .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
            .collect();
        assert_eq!(rows.len(), 4);
        rows
    };
    for (soft, stiff) in last("soft").iter().zip(last("stiff")) {
        assert!(*soft < 0.0 && ((stiff - soft) / soft - 1.0).abs() < 1e-9);
    }

    // The Pareto front of the curve difference against time: the reference is the truth (not
    // on it), the other variants are scored at the last level only.
    assert!(out.join("pareto.png").is_file() && out.join("pareto.svg").is_file());
    for r in csv_rows(&out) {
        let on = r["variant"] == "stiff" && r["level"] == "1";
        assert_eq!(r["on_front"], on.to_string(), "{r:?}");
    }
    let s = common::summary(&out);
    assert_eq!(s["metrics"]["on_front_stiff_1"].as_f64(), Some(1.0));
    assert!(s["metrics"].get("on_front_soft_1").is_none());
}

/// A run that cannot write its files ends the study, even for a variant that may fail: the
/// next runs would meet the same full disk or missing permission. One line names the variant,
/// the level and the file (the run's folder `runs/<variant>` is a file here): an output error,
/// agreed on by the ranks, is not taken for the run's own failure.
#[test]
fn a_run_that_cannot_write_its_files_ends_the_study() {
    let dir = study_dir(
        "study_unwritable_run",
        &small_study("[[variant]]\nname = \"stuck\"\nmay_fail = true\n"),
    );
    std::fs::create_dir_all(dir.join("out/runs")).unwrap();
    std::fs::write(dir.join("out/runs/stuck"), "a file").unwrap();
    let o = run_study(&dir, &["-q"]);
    let line = one_error_line(&o);
    assert!(
        line.contains("variant 'stuck' at level 0") && line.contains("runs/stuck"),
        "{line}"
    );
}

/// A variant with `may_fail = true` (a baseline expected to break) fails without failing the
/// study: exit 0, the run recorded as failed, its curve plotted up to where it stopped.
#[test]
fn a_variant_that_may_fail_does_not_fail_the_study() {
    let crushed = r#"
[[variant]]
name = "crushed"
may_fail = true
set = { "dirichlet.0.value" = [-2.0], "dirichlet.0.curve" = { kind = "table", table = [[0.0, 0.0], [0.5, 0.05], [1.0, 1.0]] }, "steps.max_cuts" = 0 }
"#;
    let dir = block_study_dir(
        "study_curves_may_fail",
        &block_study(ONE_REFINEMENT, crushed, ""),
    );
    let o = run_study(&dir, &["-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.join("out");
    let rows = csv_rows(&out);
    assert_eq!(rows[2]["converged"], "false", "{rows:?}");
    let s = common::summary(&out);
    assert_eq!(s["metrics"]["failed_runs"].as_f64(), Some(1.0));
    assert!(curve_diff(&out, "crushed").is_some());
}

#[test]
fn curves_of_a_failed_run_hold_its_converged_steps() {
    // "crushed": the first two steps as the others (-0.05, -0.1), then a step to -1.05 that
    // inverts the element, with no cuts: it fails at step 3 with two converged steps.
    let crushed = r#"
[[variant]]
name = "crushed"
set = { "dirichlet.0.value" = [-2.0], "dirichlet.0.curve" = { kind = "table", table = [[0.0, 0.0], [0.5, 0.05], [1.0, 1.0]] }, "steps.max_cuts" = 0 }
"#;
    let dir = block_study_dir(
        "study_curves_failed",
        &block_study(ONE_REFINEMENT, crushed, ""),
    );
    let o = run_study(&dir, &["-q"]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{stdout}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].contains("1 of 3 runs failed"), "{stderr}");
    let out = dir.join("out");
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[2]["converged"], "false", "{rows:?}");

    // Plotted with its two points, compared where it overlaps the reference (-0.05, -0.1):
    // there it is the reference. The legend says where it stopped.
    let svg = std::fs::read_to_string(out.join("curves.svg")).unwrap();
    assert!(out.join("curves.png").is_file());
    if svg.contains("<text") {
        assert!(
            svg.contains("crushed: stopped at -0.100") && !svg.contains("no points"),
            "{svg}"
        );
    }
    let s = common::summary(&out);
    assert_eq!(s["converged"], false);
    assert_eq!(s["metrics"]["failed_runs"].as_f64(), Some(1.0));
    let d = curve_diff(&out, "crushed").expect("curve_max_rel_diff_crushed");
    assert!(d < 1e-9, "{d}");
    assert!((curve_diff(&out, "stiff").unwrap() - 1.0).abs() < 1e-9);
    // One refinement: no slope, no convergence plot.
    assert!(s["metrics"].get("slope_soft").is_none(), "{s}");
    assert!(!out.join("convergence.png").exists());
}

#[test]
fn bad_curve_column_stops_the_study_after_one_run() {
    let dir = block_study_dir(
        "study_curves_bad_column",
        &block_study(ONE_REFINEMENT, "", "")
            .replace("y = \"reaction_b.zmax_z\"", "y = \"reaction_b.zmax_w\""),
    );
    let o = run_study(&dir, &["-q"]);
    let stderr = text(&o.stderr);
    assert!(!o.status.success());
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    let line = lines[0];
    assert!(line.starts_with("mortar: error: "), "{stderr}");
    for part in [
        "study.toml",
        "curves.y = \"reaction_b.zmax_w\": no such column",
        "history.csv",
        "reaction_b.zmax_z, ",
        "u_b.zmax_z",
    ] {
        assert!(line.contains(part), "no '{part}' in: {stderr}");
    }
    let out = dir.join("out");
    assert!(out.join("runs/soft/0/history.csv").is_file());
    assert!(!out.join("runs/stiff").exists(), "no run after the first");
}

/// A sweep on one mesh (no `[curves]`, one refinement): no slope and no convergence plot, but
/// the Pareto plot and `study.csv`; every converged run's own metrics, wall time and peak
/// memory reach the study summary as `<metric>_<variant>_<level>`, where expectations bound
/// them (a bound one run breaks fails the study, naming that run's value).
#[test]
fn a_sweep_on_one_mesh_bounds_each_runs_metrics() {
    let study = block_study(ONE_REFINEMENT, "", "");
    let sweep = |expect: &str| {
        let mut s = study[..study.find("[curves]").unwrap()].to_string();
        s.insert_str(
            s.find("[[refinement]]").unwrap(),
            &format!("expect = {expect}\n"),
        );
        s
    };
    let dir = block_study_dir(
        "study_one_mesh",
        &sweep(r#"["max_newton_its_* <= 8", "peak_memory_mb_soft_0 > 0", "seconds_* > 0"]"#),
    );
    let o = run_study(&dir, &["-q"]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    let out = dir.join("out");
    assert_eq!(csv_rows(&out).len(), 2);
    assert!(out.join("pareto.svg").is_file());
    assert!(
        !out.join("convergence.png").exists(),
        "no convergence plot on one mesh"
    );
    let s = common::summary(&out);
    let m = &s["metrics"];
    assert!(m.get("slope_soft").is_none(), "{s}");
    for v in ["soft", "stiff"] {
        let its = |k: &str| {
            m[format!("{k}_{v}_0")]
                .as_f64()
                .unwrap_or_else(|| panic!("{k} {s}"))
        };
        // The study's metric is the run's own `total_newton_its`, under both names.
        assert_eq!(its("total_newton_its"), its("error"));
        assert!(its("max_newton_its") >= 1.0 && its("max_newton_its") <= its("total_newton_its"));
        assert!(its("seconds") > 0.0 && its("peak_memory_mb") > 0.0);
    }
    for line in [
        "expect max_newton_its_* <= 8: max_newton_its_soft_0 = ",
        "expect seconds_* > 0: seconds_soft_0 = ",
    ] {
        assert!(stdout.contains(line), "no '{line}' in:\n{stdout}");
    }

    // A bound the runs break: the study fails and names the offending value.
    let failing = block_study_dir(
        "study_one_mesh_failing",
        &sweep(r#"["max_newton_its_* < 1"]"#),
    );
    let o = run_study(&failing, &["-q"]);
    assert!(!o.status.success());
    let stdout = text(&o.stdout);
    assert!(
        stdout.contains("expect max_newton_its_* < 1: max_newton_its_soft_0 = ")
            && stdout.contains("-> FAILED"),
        "{stdout}"
    );
}

#[test]
fn curves_keys_are_checked() {
    let expect_error = |name: &str, study: &str, parts: &[&str]| {
        let dir = block_study_dir(name, study);
        let o = run_study(&dir, &["-q"]);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{name}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.starts_with("mortar: error: "), "{stderr}");
        for part in parts {
            assert!(stderr.contains(part), "no '{part}' in: {stderr}");
        }
        assert!(!dir.join("out").exists(), "nothing runs before validation");
    };
    expect_error(
        "study_curves_unknown_key",
        &block_study(ONE_REFINEMENT, "", "colour = \"red\""),
        &["study.toml", "colour"],
    );
    expect_error(
        "study_curves_bad_reference",
        &block_study(ONE_REFINEMENT, "", "")
            .replace("reference = \"soft\"", "reference = \"hard\""),
        &["curves.reference = \"hard\": no such variant (variants: soft, stiff)"],
    );
    expect_error(
        "study_curves_nan_after",
        &block_study(ONE_REFINEMENT, "", "after = nan"),
        &["curves.after"],
    );
}

/// The knobs a study sweeps besides the case's keys, on a 2-rank job: a variant on 1 rank
/// (`ranks = 1`) gives the 2-rank run's error to 1e-10 relative; a variant's PETSc options
/// reach its runs only (an impossible `-ksp_type` fails that variant's runs, and the variants
/// after it run as before); `-pc_type` alone gets GMRES around it (the solver's defaults of the
/// earlier runs, `-ksp_type preonly` among them, do not leak into it) and gives the direct
/// solve's error; an option of a variant that nothing reads draws a warning naming it and the
/// variant (also when it overrides an option already set), and options that were read draw
/// none.
#[test]
fn variants_sweep_ranks_and_petsc_options() {
    // Every run made twice (`repeat`): collective on 2 ranks, also for the 1-rank variant.
    let dir = study_dir(
        "study_ranks_options",
        &format!(
            "repeat = 2\n{}",
            small_study(
                r#"
[[variant]]
name = "two_ranks"

[[variant]]
name = "one_rank"
ranks = 1
petsc = "-no_such_option 1"

[[variant]]
name = "bogus_solver"
petsc = "-ksp_type no_such_solver"
may_fail = true

[[variant]]
name = "gmres"
petsc = "-pc_type jacobi -ksp_rtol 1e-13 -ksp_max_it 5000 -mat_mumps_icntl_8 77"
"#,
            )
        ),
    );
    let out = dir.join("out");
    // The command line sets an option the gmres variant overrides (and, without MUMPS, does
    // not read), while the other variants read it.
    let o = common::run_subcommand(
        "study",
        &dir.join("study.toml"),
        2,
        &out,
        &["-mat_mumps_icntl_8", "0"],
    );
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", text(&o.stderr));
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 8, "{rows:?}");
    let row = |v: &str, level: &str| {
        rows.iter()
            .find(|r| r["variant"] == v && r["level"] == level)
            .unwrap_or_else(|| panic!("no {v} {level} in {rows:?}"))
    };
    for level in ["0", "1"] {
        let error = |v: &str| row(v, level)["error"].parse::<f64>().unwrap();
        assert_eq!(row("two_ranks", level)["ranks"], "2");
        assert_eq!(row("one_rank", level)["ranks"], "1");
        let (two, one, gmres) = (error("two_ranks"), error("one_rank"), error("gmres"));
        assert!((one - two).abs() <= 1e-10 * two, "{one} vs {two}");
        assert!((gmres - two).abs() <= 1e-6 * two, "{gmres} vs {two}");
        let bogus = row("bogus_solver", level);
        assert_eq!(bogus["converged"], "false", "{bogus:?}");
        assert!(bogus["error"].is_empty());
        // A failed run is not repeated; a converged one may be slower on its repeat, never
        // faster than the time kept.
        assert_eq!(bogus["seconds"], bogus["seconds_slowest"], "{bogus:?}");
        for v in ["two_ranks", "one_rank", "gmres"] {
            let r = row(v, level);
            let time = |k: &str| r[k].parse::<f64>().unwrap();
            assert!(time("seconds") <= time("seconds_slowest"), "{r:?}");
        }
    }
    // An option no PETSc object reads draws a warning naming the variant, also when it
    // overrides one the command line set; options that were read do not. The command line's
    // option, read by the other variants, keeps its mark after the override: no warning at
    // the end.
    let stderr = text(&o.stderr);
    assert!(
        stderr.contains("variant 'one_rank': PETSc option(s) -no_such_option not used"),
        "{stderr}"
    );
    let warned = |variant: &str| {
        stderr
            .matches(&format!("variant '{variant}': PETSc option(s)"))
            .count()
    };
    assert!(
        stderr.contains("variant 'gmres': PETSc option(s) -mat_mumps_icntl_8 not used"),
        "{stderr}"
    );
    assert_eq!(
        (warned("one_rank"), warned("gmres")),
        (1, 1),
        "once per variant"
    );
    assert!(!stderr.contains("never used"), "{stderr}");
    let s = common::summary(&out);
    assert!(
        s["message"].as_str().unwrap().contains("no_such_solver"),
        "{s}"
    );
    // The first variant has no edits: it is the study's defaults.
    assert!(s["metrics"]["default_on_front"].as_f64().is_some(), "{s}");
}

/// One Hex8 refinement (n = 2) of the thick sphere, the variants `hex8` (the case) and `failing`
/// (a KSP type that does not exist: its run fails), and the study keys `keys`.
fn study_with_a_failing_variant(keys: &str, failing: &str) -> String {
    format!(
        r#"
case = "case.toml"
metric = "energy_error"
{keys}

[[refinement]]
h = 0.5
set = {{ "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2, "mesh.0.element" = "hex8" }}

[[variant]]
name = "hex8"

[[variant]]
name = "{failing}"
petsc = "-ksp_type no_such_solver"
"#
    )
}

/// A study on 2 ranks whose runs fail (not allowed to) still prints its expectations, once (rank
/// 0), then fails in one error line from rank 0, and both ranks stop: no hang under
/// `mpirun --timeout`.
#[test]
fn failed_runs_on_two_ranks_print_the_expectations_once() {
    let dir = study_dir(
        "study_failed_two_ranks",
        &study_with_a_failing_variant(r#"expect = ["error_hex8_0 > 0"]"#, "bogus_solver"),
    );
    let out = dir.join("out");
    let o = common::run_subcommand("study", &dir.join("study.toml"), 2, &out, &["-q"]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{stdout}");
    assert_eq!(
        stdout
            .matches("expect error_hex8_0 > 0: error_hex8_0 = ")
            .count(),
        1,
        "{stdout}"
    );
    assert!(stdout.trim_end().ends_with("-> ok"), "{stdout}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("mortar: error: "))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(errors[0].contains("1 of 2 runs failed"), "{stderr}");
}

/// A variant's solver package that PETSc lacks, in a study on 2 ranks: found when the run sets
/// up its solver (on every rank alike), so the run is recorded as failed and the study goes on,
/// and the one error line names the variant, the level and the variant's `petsc` as a source
/// (not a line of each rank aborting the job in the first solve, and no CSV).
#[test]
fn a_variants_missing_solver_package_on_two_ranks_names_the_variant() {
    let study = study_with_a_failing_variant("", "nopackage").replace(
        "-ksp_type no_such_solver",
        "-pc_factor_mat_solver_type nonexistent",
    );
    let dir = study_dir("study_missing_package_two_ranks", &study);
    let out = dir.join("out");
    let o = common::run_subcommand("study", &dir.join("study.toml"), 2, &out, &["-q"]);
    let stderr = text(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("mortar: error: "))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    for part in [
        "1 of 2 runs failed",
        "nopackage level 0",
        "the study variant's `petsc`",
        "nonexistent for factorization type LU",
    ] {
        assert!(errors[0].contains(part), "{part}: {}", errors[0]);
    }
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert_eq!(rows[0]["converged"], "true", "{rows:?}");
    assert_eq!(rows[1]["converged"], "false", "{rows:?}");
}

/// A `finest_reference` run that fails leaves no run an error: the study fails, naming it, after
/// printing its expectations on what the other runs measured.
#[test]
fn a_failed_finest_reference_still_prints_the_expectations() {
    let dir = study_dir(
        "study_failed_reference",
        &study_with_a_failing_variant(
            "finest_reference = \"truth\"\nexpect = [\"energy_error_hex8_0 > 0\"]",
            "truth",
        ),
    );
    let o = run_study(&dir, &["-q"]);
    let stdout = text(&o.stdout);
    let line = one_error_line(&o);
    assert!(
        line.contains("the finest_reference run (truth at level 0) failed"),
        "{line}"
    );
    assert!(
        stdout.contains("expect energy_error_hex8_0 > 0: energy_error_hex8_0 = ")
            && stdout.trim_end().ends_with("-> ok"),
        "{stdout}"
    );
}

/// `metric` as a list: a run's error is the largest of the metrics (checked against each run's
/// own summary); a negative `error_floor`, an `error_noise` NaN and a `time_noise` of 1 or more
/// are refused with one line naming the key.
#[test]
fn the_error_may_be_the_largest_of_several_metrics() {
    let study = small_study("[[variant]]\nname = \"hex8\"\n").replace(
        "metric = \"energy_error\"",
        "metric = [\"energy_error\", \"free_dofs\"]",
    );
    let dir = study_dir("study_metric_list", &study);
    let o = run_study(&dir, &["-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.join("out");
    for r in csv_rows(&out) {
        let run = common::summary(&out.join(format!("runs/hex8/{}", r["level"])));
        let m = |k: &str| run["metrics"][k].as_f64().unwrap();
        let want = m("energy_error").abs().max(m("free_dofs"));
        assert_eq!(r["error"].parse::<f64>().unwrap(), want, "{r:?}");
    }

    // A bad top-level key: one line naming it, and a failure.
    for (name, line, says) in [
        (
            "study_error_floor",
            "error_floor = -1.0",
            "error_floor = -1: must be",
        ),
        (
            "study_error_noise",
            "error_noise = nan",
            "error_noise = NaN: must be",
        ),
        (
            "study_repeat",
            "repeat = 0",
            "repeat = 0: must be from 1 to 10",
        ),
        (
            "study_time_noise",
            "time_noise = 1.5",
            "time_noise = 1.5: must be",
        ),
    ] {
        let study = format!("{line}\n{}", small_study("[[variant]]\nname = \"a\"\n"));
        let o = run_study(&study_dir(name, &study), &["-q"]);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{line}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
}

/// The contact patch's study as shipped, from its file: every run converges, the
/// CSV and both plots (PNG and SVG) are written, its expectations (every one-pass mortar
/// variant exact to 1e-10 at every level) are printed as met, and no run on the Pareto front is
/// beaten in both error and time by another, with the study's own ties (errors at or below its
/// `error_floor` equal, times within its `time_noise` equal).
#[test]
fn shipped_contact_patch_study_runs_from_its_file() {
    let scene = common::scene_dir("contact_patch");
    let dir = common::fresh_dir("study_contact_patch_shipped");
    for f in ["case.toml", "petscrc", "study.toml"] {
        std::fs::copy(scene.join(f), dir.join(f)).unwrap();
    }
    let o = run_study(&dir, &["-q"]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    let met: Vec<&str> = stdout.lines().filter(|l| l.contains("expect ")).collect();
    assert_eq!(met.len(), 3, "{stdout}");
    assert!(met.iter().all(|l| l.ends_with("-> ok")), "{stdout}");
    let out = dir.join("out");
    for plot in ["pareto", "convergence"] {
        for ext in ["png", "svg"] {
            assert!(out.join(format!("{plot}.{ext}")).is_file(), "{plot}.{ext}");
        }
    }
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 12, "6 variants x 2 levels: {rows:?}");
    assert!(rows.iter().all(|r| r["converged"] == "true"), "{rows:?}");
    let (floor, noise) = (1e-10, 0.1);
    let file = std::fs::read_to_string(dir.join("study.toml")).unwrap();
    assert!(file.contains("error_floor = 1e-10") && file.contains("time_noise = 0.1"));
    let runs: Vec<(f64, f64, bool)> = rows
        .iter()
        .map(|r| {
            let value = |k: &str| r[k].parse::<f64>().unwrap();
            (value("seconds"), value("error"), r["on_front"] == "true")
        })
        .collect();
    let same_time = |a: f64, b: f64| (a - b).abs() <= noise * a.max(b);
    let same_error = |a: f64, b: f64| a.max(b) <= floor || (a - b).abs() <= 1e-9 * a.max(b);
    let beats = |q: (f64, f64, bool), p: (f64, f64, bool)| {
        let (no_slower, no_worse) = (
            q.0 <= p.0 || same_time(q.0, p.0),
            q.1 <= p.1 || same_error(q.1, p.1),
        );
        let strictly = (q.0 < p.0 && !same_time(q.0, p.0)) || (q.1 < p.1 && !same_error(q.1, p.1));
        no_slower && no_worse && strictly
    };
    assert!(runs.iter().any(|r| r.2), "an empty front: {rows:?}");
    for (i, &p) in runs.iter().enumerate().filter(|(_, r)| r.2) {
        for (j, &q) in runs.iter().enumerate() {
            assert!(!beats(q, p), "run {j} beats run {i} on the front: {rows:?}");
        }
    }
}

/// `finest_reference`: for a metric that is a value, every run's error is its relative
/// difference to the reference variant's finest run (checked against each run's own summary),
/// the reference run has none (not on the front), the finest is the smallest h whatever the
/// order of the refinements, the values are kept in the summary; a bad `finest_reference` (no
/// such variant, with `[curves]`, with a list of metrics) is refused in one line naming the
/// key.
#[test]
fn errors_may_be_taken_against_the_finest_run() {
    let variants = "[[variant]]\nname = \"a\"\n\n[[variant]]\nname = \"hex8\"\n\
                    set = { \"mesh.0.element\" = \"hex8\" }\n";
    // The refinements listed finest first: the truth is the smallest h, level 0.
    let coarse = "[[refinement]]\nh = 0.5\nset = { \"mesh.0.n_circ\" = 2, \"mesh.0.n_rad\" = 2 }\n";
    let fine = "[[refinement]]\nh = 0.3333333333333333\n\
                set = { \"mesh.0.n_circ\" = 3, \"mesh.0.n_rad\" = 3 }\n";
    let study = small_study(variants);
    assert!(study.contains(coarse) && study.contains(fine));
    let study = study.replacen(coarse, "", 1).replacen(fine, "", 1);
    let study = format!("finest_reference = \"a\"\n{study}\n{fine}\n{coarse}");
    let dir = study_dir("study_finest_reference", &study);
    let o = run_study(&dir, &["-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.join("out");
    let value = |v: &str, level: &str| {
        common::summary(&out.join(format!("runs/{v}/{level}")))["metrics"]["energy_error"]
            .as_f64()
            .unwrap()
    };
    let truth = value("a", "0");
    let s = common::summary(&out);
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 4);
    for r in rows {
        let (v, level) = (r["variant"].as_str(), r["level"].as_str());
        let m = value(v, level);
        assert_eq!(s["metrics"][format!("value_{v}_{level}")].as_f64(), Some(m));
        if (v, level) == ("a", "0") {
            assert!(r["error"].is_empty(), "{r:?}");
            assert_eq!(r["on_front"], "false");
            continue;
        }
        let want = (m - truth).abs() / truth.abs();
        assert!(want > 1e-6, "{r:?}: the runs' values differ");
        let error: f64 = r["error"].parse().unwrap();
        assert!((error - want).abs() <= 1e-12 * want, "{r:?}: {want}");
        let in_summary = s["metrics"][format!("error_{v}_{level}")].as_f64().unwrap();
        assert!(
            (in_summary - want).abs() <= 1e-12 * want,
            "{in_summary} against {want}"
        );
    }
    assert!(out.join("pareto.png").is_file() && out.join("convergence.png").is_file());

    let one = small_study("[[variant]]\nname = \"a\"\n");
    for (name, study, says) in [
        (
            "study_finest_no_variant",
            format!("finest_reference = \"nope\"\n{one}"),
            "finest_reference = \"nope\": no such variant",
        ),
        (
            "study_finest_with_curves",
            format!(
                "finest_reference = \"a\"\n{one}\n[curves]\nx = \"load\"\ny = \"load\"\n\
                 reference = \"a\"\n"
            ),
            "not with [curves]",
        ),
        (
            "study_finest_metric_list",
            format!(
                "finest_reference = \"a\"\n{}",
                one.replace(
                    "metric = \"energy_error\"",
                    "metric = [\"energy_error\", \"free_dofs\"]"
                )
            ),
            "needs one metric, not a list",
        ),
    ] {
        let o = run_study(&study_dir(name, &study), &["-q"]);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{name}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
}

/// A study run again into the same folder: a run that fails now leaves none of the outputs of
/// the earlier study's run of the same name, whose `summary.json` (converged) would be read for
/// the failed run's Newton iterations.
#[test]
fn a_rerun_into_the_same_folder_keeps_nothing_of_the_last() {
    let failing = study_with_a_failing_variant("", "late");
    let working = failing.replace("petsc = \"-ksp_type no_such_solver\"\n", "");
    assert_ne!(working, failing);
    let dir = study_dir("study_rerun_same_folder", &working);
    let first = run_study(&dir, &["-q"]);
    assert!(first.status.success(), "{}", text(&first.stderr));
    let out = dir.join("out");
    let late = |rows: &[BTreeMap<String, String>]| {
        rows.iter()
            .find(|r| r["variant"] == "late")
            .cloned()
            .unwrap()
    };
    let before = late(&csv_rows(&out));
    assert_eq!(before["converged"], "true", "{before:?}");
    let run_dir = out.join("runs/late/0");
    assert!(run_dir.join("summary.json").is_file());

    std::fs::write(dir.join("study.toml"), &failing).unwrap();
    let second = run_study(&dir, &["-q"]);
    assert!(!second.status.success(), "{}", text(&second.stdout));
    let after = late(&csv_rows(&out));
    assert_eq!(after["converged"], "false", "{after:?}");
    assert_eq!(after["newton_its"], "0", "{after:?}");
    assert!(
        !run_dir.join("summary.json").is_file() && !run_dir.join("history.csv").is_file(),
        "outputs of the first study left in {}",
        run_dir.display()
    );
}

/// `default_on_front` counts the default variant's failed runs, off the front: here the case as
/// it is converges on the coarse level and fails on the second (a finite-strain material, one
/// Newton iteration allowed, a tolerance no iteration meets), so it has 1 of 2 runs on the
/// front.
#[test]
fn failed_runs_of_the_defaults_count_off_the_front() {
    let study = r#"
case = "case.toml"
metric = "energy_error"

[[refinement]]
h = 0.5
set = { "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2, "mesh.0.element" = "hex8" }

[[refinement]]
h = 0.25
set = { "mesh.0.n_circ" = 2, "mesh.0.n_rad" = 2, "mesh.0.element" = "hex8", "material.0.model" = "neo_hookean", "newton.max_it" = 1, "newton.rtol" = 1e-30, "newton.atol" = 1e-40, "steps.predictor" = false, "steps.max_cuts" = 0 }

[[variant]]
name = "defaults"
may_fail = true
"#;
    let dir = study_dir("study_defaults_failing", study);
    let o = run_study(&dir, &[]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    assert!(
        stdout.contains("the defaults (variant 'defaults') have 1 of 2 runs on it"),
        "{stdout}"
    );
    let s = common::summary(&dir.join("out"));
    assert_eq!(s["metrics"]["default_on_front"], 0.5, "{s}");
}

/// With `[curves]`, `default_on_front` counts the defaults' runs of the last level only, where
/// curves are scored: here `soft` (the case as it is) against the reference `stiff`, on 2
/// levels, has 1 of 1 runs on the front (its level-0 run has no error to place, and is not a
/// failure).
#[test]
fn curves_count_the_defaults_at_the_last_level() {
    let refinements = TWO_REFINEMENTS;
    let study =
        block_study(refinements, "", "").replace("reference = \"soft\"", "reference = \"stiff\"");
    assert!(study.contains("reference = \"stiff\""));
    let dir = block_study_dir("study_curves_defaults", &study);
    let o = run_study(&dir, &[]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    assert!(
        stdout.contains("the defaults (variant 'soft') have 1 of 1 runs on it"),
        "{stdout}"
    );
    let s = common::summary(&dir.join("out"));
    assert_eq!(s["metrics"]["default_on_front"], 1.0, "{s}");
}

/// A variant that asks for more ranks than the job has: one error line naming its key, and no
/// output folder left behind.
#[test]
fn a_variant_on_more_ranks_than_the_job_is_refused_cleanly() {
    let study = study_with_a_failing_variant("", "wide")
        .replace("petsc = \"-ksp_type no_such_solver\"", "ranks = 2");
    assert!(study.contains("ranks = 2"));
    let dir = study_dir("study_too_many_ranks", &study);
    let line = one_error_line(&run_study(&dir, &["-q"]));
    assert!(line.contains("variant[1].ranks = 2"), "{line}");
    assert!(
        !dir.join("out").exists(),
        "an output folder was left behind"
    );
}

/// A folder with the slide case and a study of it whose first variant (and the warm-up, a run
/// of it) is short and whose second is long (2 000 steps): a study that can be caught inside
/// its second run.
fn long_study_dir(name: &str) -> PathBuf {
    let dir = common::fresh_dir(name);
    std::fs::write(dir.join("case.toml"), common::slide_case(2000)).unwrap();
    let mut study = String::from(
        "case = \"case.toml\"\nmetric = \"max_newton_its\"\ntitle = \"t\"\n\
         [[refinement]]\nh = 1.0\nset = {}\n",
    );
    for (name, set) in [
        ("a", "\"steps.count\" = 20"),
        ("b", "\"interface.0.friction\" = 0.2"),
        ("c", "\"interface.0.friction\" = 0.1"),
    ] {
        study += &format!("[[variant]]\nname = \"{name}\"\nset = {{ {set} }}\n");
    }
    std::fs::write(dir.join("study.toml"), study).unwrap();
    dir
}

/// Ctrl-C (SIGINT) during a study's second run: the study stops there with exit status 130 and
/// one line naming the signal, the run and where the finished run is; `study.csv` holds that
/// run alone.
#[test]
fn an_interrupted_study_keeps_the_runs_it_finished() {
    let dir = long_study_dir("study_interrupted");
    let out_dir = dir.join("out");
    let run = common::subcommand("study", &dir.join("study.toml"), 1, &out_dir, &[]);
    let o = common::run_and_signal(run, "  a level 0 ", "INT", 0);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{:?}: {}",
        o.status,
        text(&o.stderr)
    );
    let line = one_error_line(&o);
    let said = format!(
        "interrupted by SIGINT at study {}: variant 'b' at level 0: 1 finished run(s) in {}",
        dir.join("study.toml").display(),
        out_dir.join("study.csv").display()
    );
    assert_eq!(line, format!("mortar: error: {said}"));
    let rows = csv_rows(&out_dir);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!(rows[0]["variant"], "a");
}

/// A second study into the folder of a running one is refused at once, with one line naming
/// the folder (instead of emptying the first one's run folders and writing beside it); the
/// first goes on, its finished run intact.
#[test]
fn a_study_into_the_folder_of_a_running_one_is_refused() {
    let dir = long_study_dir("study_folder_in_use");
    let out_dir = dir.join("out");
    let study =
        |args: &[&str]| common::subcommand("study", &dir.join("study.toml"), 1, &out_dir, args);
    let first = common::start_until(study(&[]), "  a level 0 ");
    // Held still while the second study starts, so that it surely meets the first one.
    first.signal(0, "STOP");
    let second = study(&["-q"]).output().unwrap();
    first.signal(0, "CONT");
    let line = one_error_line(&second);
    let said = format!(
        "mortar: error: output: {}: another run is writing into this folder",
        out_dir.display()
    );
    assert!(line.starts_with(&said), "{line}");
    assert_eq!(second.status.code(), Some(1));
    // The first study: its run of 'a' still there; ended early by a Ctrl-C.
    first.signal(0, "INT");
    let first = first.finish();
    assert_eq!(first.status.code(), Some(130), "{}", text(&first.stderr));
    let rows = csv_rows(&out_dir);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!(rows[0]["variant"], "a");
    assert!(out_dir.join("runs/a/0/summary.json").is_file());
}
