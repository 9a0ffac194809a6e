//! A run stopped by a signal: a closed stdout (SIGPIPE) ends it quietly, Ctrl-C (SIGINT) stops
//! it with its finished steps on disk, a SIGINT ignored at its start stays ignored, and SIGTERM
//! to one rank of two stops both.

mod common;

use std::process::Command;

/// A reader that stops early (`mortar run ... | head -1`) ends the run as it ends any program,
/// by SIGPIPE at its next progress line, without PETSc's crash report ("Caught signal number
/// 13 Broken Pipe ... Try option -start_in_debugger") and without a panic; the steps before
/// it are on disk, `summary.json` included (a step's line comes after its files).
#[test]
fn a_closed_stdout_ends_the_run_quietly() {
    use std::io::BufRead;
    let case = common::write_case("closed_stdout", &common::slide_case(5));
    let out_dir = case.parent().unwrap().join("out");
    let mut child = common::mortar_command()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(&out_dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("mortar: "), "{first}");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("Caught signal") && !stderr.contains("panicked"),
        "{stderr}"
    );
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(out.status.signal(), Some(13), "{:?}", out.status);
}

/// Ctrl-C (SIGINT) stops a run at its next step or Newton iteration: exit status 130, one line
/// naming the signal and the last finished step, a summary that says the same, and the
/// finished steps, and only they, in the history. The steps of this scene take several Newton
/// iterations, so the stop comes inside a solve, and the state must be restored to the last
/// finished step.
#[test]
fn an_interrupted_run_stops_with_its_finished_steps_on_disk() {
    let toml = common::slide_case(100) + "[output]\ntrack = [\"up.zmin\"]\n";
    let case = common::write_case("interrupted", &toml);
    let out_dir = case.parent().unwrap().join("out");
    let run = common::subcommand("run", &case, 1, &out_dir, &[]);
    let out = common::run_and_signal(run, "  step 2 ", "INT", 0);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{:?}: {stderr}", out.status);
    let s = common::summary(&out_dir);
    let steps = s["steps"].as_array().unwrap().len();
    assert!((2..100).contains(&steps), "{steps} steps");
    let said = format!("interrupted by SIGINT after step {steps} (load ");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with(&format!("mortar: error: {said}")),
        "{}",
        lines[0]
    );
    assert!(
        s["message"].as_str().unwrap().starts_with(&said),
        "{}",
        s["message"]
    );
    assert_eq!(
        (&s["completed"], &s["converged"]),
        (&false.into(), &false.into())
    );
    let history = std::fs::read_to_string(out_dir.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), steps + 1, "{history}");
    // The end of a failed run: the last finished step's displacements (not the stopped
    // iterate's): their mean over the secondary face equals the history's last row.
    assert!(
        s["metrics"]["max_displacement"].as_f64().unwrap() > 0.0,
        "{s}"
    );
    let face: Vec<[f64; 6]> = common::displacements(&out_dir)
        .into_iter()
        .filter(|r| {
            (r[2] - 0.5).abs() < 1e-12 && [0.25, 0.6, 0.95].iter().any(|x| (r[0] - x).abs() < 1e-12)
        })
        .collect();
    assert_eq!(face.len(), 9);
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let last_row: Vec<f64> = history
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        let column = format!("track_up.zmin_{name}");
        let tracked = last_row[header.iter().position(|h| *h == column).unwrap()];
        let mean = face.iter().map(|r| r[3 + axis]).sum::<f64>() / 9.0;
        assert!(
            (mean - tracked).abs() <= 1e-12 * tracked.abs().max(1e-9),
            "{column}: {mean} in displacement.csv, {tracked} in history.csv"
        );
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let last = stdout.trim_end().lines().last().unwrap_or_default();
    let said = format!("mortar: interrupted: {steps} steps, ");
    assert!(last.starts_with(&said), "{stdout}");
    assert!(
        last.ends_with(&format!(" -> {}", out_dir.display())),
        "{stdout}"
    );
}

/// A run started with SIGINT ignored (a background job of a script) keeps ignoring it: the
/// signal changes nothing.
#[test]
fn a_run_started_with_sigint_ignored_keeps_ignoring_it() {
    let case = common::write_case("ignored_sigint", &common::slide_case(200));
    let out_dir = case.parent().unwrap().join("out");
    let mut run = Command::new("sh");
    run.args([
        "-c",
        "trap '' INT; exec \"$0\" \"$@\"",
        env!("CARGO_BIN_EXE_mortar"),
        "run",
    ])
    .arg(&case)
    .arg("--out")
    .arg(&out_dir);
    common::mpi_env(&mut run);
    let out = common::run_and_signal(run, "  step 2 ", "INT", 0);
    assert!(
        out.status.success(),
        "{:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let s = common::summary(&out_dir);
    assert_eq!(s["converged"], true);
    assert_eq!(s["steps"].as_array().unwrap().len(), 200);
}

/// SIGTERM to one rank of two stops both at the same point (they poll the signal together,
/// here inside a Newton solve: the steps take several iterations): exit status 143, one line,
/// and rank 0's summary and history with the steps finished.
#[test]
fn a_signal_to_one_rank_stops_both() {
    let case = common::write_case("interrupted_two_ranks", &common::slide_case(100));
    let out_dir = case.parent().unwrap().join("out");
    let run = common::subcommand("run", &case, 2, &out_dir, &[]);
    let out = common::run_and_signal(run, "  step 2 ", "TERM", 1);
    let line = common::the_error_line(&out, "SIGTERM to rank 1");
    assert_eq!(out.status.code(), Some(143), "{:?}", out.status);
    let s = common::summary(&out_dir);
    let steps = s["steps"].as_array().unwrap().len();
    assert!((2..100).contains(&steps), "{steps} steps");
    let said = format!("interrupted by SIGTERM after step {steps} (load ");
    assert!(
        line.starts_with(&format!("mortar: error: {said}")),
        "{line}"
    );
    assert!(
        s["message"].as_str().unwrap().starts_with(&said),
        "{}",
        s["message"]
    );
    let history = std::fs::read_to_string(out_dir.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), steps + 1, "{history}");
}
