//! `mortar study`: a small convergence study of the thick sphere (Hex8 and Hex20, n = 2, 3; small
//! enough for a debug build), a study with an impossible path, and a study with failing runs.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mortar::io::plot::fitted_slope;

/// A fresh folder with a copy of the thick-sphere case and `study.toml` = `study`.
fn study_dir(name: &str, study: &str) -> PathBuf {
    let dir = common::fresh_dir(name);
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/thick_sphere");
    for f in ["case.toml", "petscrc"] {
        std::fs::copy(case.join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("study.toml"), study).unwrap();
    dir
}

/// Runs `mortar study DIR/study.toml --out DIR/out ARGS` on one rank.
fn run_study(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mortar"))
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_mpi_yield_when_idle", "1")
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

/// study.csv as rows of fields (header skipped).
fn csv_rows(out: &Path) -> Vec<Vec<String>> {
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("variant,level,h,error,seconds,newton_its,converged")
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
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
        assert_eq!((row[0].as_str(), row[1].as_str()), (variant, level));
        assert!(row[3].parse::<f64>().unwrap() > 0.0, "{row:?}");
        assert_eq!(row[6], "true");
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
    assert_eq!(s["case"], "study");
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
    assert_eq!(e, rows[3][3].parse::<f64>().unwrap());
    // The slope is the one of the table's points.
    let pts: Vec<(f64, f64)> = rows[..2]
        .iter()
        .map(|r| (r[2].parse().unwrap(), r[3].parse().unwrap()))
        .collect();
    assert!((fitted_slope(&pts) - s8).abs() < 1e-12);
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
    let o = run_study(&dir, &["-q"]);
    let stderr = text(&o.stderr);
    assert!(!o.status.success());
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].starts_with("mortar: error: "), "{stderr}");
    assert!(
        lines[0].contains("variant[0].set.\"mesh.3.element\""),
        "{stderr}"
    );
    assert!(lines[0].contains("study.toml"), "{stderr}");
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
    let o = run_study(&dir, &["-q"]);
    let stderr = text(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("elemnt") && stderr.contains("variant 'hex8'"),
        "{stderr}"
    );
}

#[test]
fn failed_runs_are_recorded_and_the_study_goes_on() {
    // "stuck": one Newton iteration allowed, a tolerance no iteration meets, no cuts.
    let dir = study_dir(
        "study_failed_runs",
        &small_study(
            r#"
[[variant]]
name = "stuck"
set = { "mesh.0.element" = "hex8", "newton.max_it" = 1, "newton.rtol" = 1e-30, "newton.atol" = 1e-40, "steps.predictor" = false, "steps.max_cuts" = 0 }

[[variant]]
name = "hex8"
set = { "mesh.0.element" = "hex8" }
"#,
        ),
    );
    let o = run_study(&dir, &["-q"]);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{stdout}");
    assert!(stdout.is_empty(), "-q: {stdout}");
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
        let stuck = r[0] == "stuck";
        assert_eq!(r[6], if stuck { "false" } else { "true" }, "{r:?}");
        assert_eq!(r[3].is_empty(), stuck, "{r:?}");
    }
    let s = common::summary(&out);
    assert_eq!(s["converged"], false);
    assert!(s["metrics"]["slope_hex8"].as_f64().unwrap() > 0.5);
    assert!(s["metrics"].get("slope_stuck").is_none());
    assert_eq!(s["metrics"]["failed_runs"].as_f64(), Some(2.0));
    assert!(s["message"].as_str().unwrap().contains("stuck level 0"));
    assert!(out.join("convergence.png").is_file() && out.join("convergence.svg").is_file());
}
