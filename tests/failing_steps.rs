//! A step that fails: cut and retried, a clear failure when it may not be cut, or accepted and
//! recorded when the case asks to go on (`steps.on_failure = "continue"`).

mod common;

/// A block compressed 60 % in one step, without the predictor, inverts its top elements on the
/// first Newton iterate: the step is cut (reported), and the halved steps converge. (With the
/// default predictor the same step converges in 4 iterations, checked too.)
#[test]
fn a_failing_step_is_cut_and_retried() {
    let case = common::write_case(
        "cut_block",
        &common::compressed_block_no_predictor("hex8", 0.6, 1),
    );
    let (out, stdout) = common::run_case(&case, 1, &[]);
    let s = common::summary(&out);
    assert_eq!(s["converged"], true);
    assert_eq!(s["completed"], true);
    let steps = s["steps"].as_array().unwrap();
    assert!(steps.len() > 1, "expected the single step to be split");
    let cuts: u64 = steps.iter().map(|st| st["cut"].as_u64().unwrap()).sum();
    assert!(cuts >= 1, "no cut recorded: {steps:?}");
    assert!(stdout.contains("cut 1/"), "cut not reported:\n{stdout}");
    assert_eq!(steps.last().unwrap()["load"].as_f64().unwrap(), 1.0);

    let with_predictor = common::write_case(
        "cut_block_predictor",
        &common::compressed_block("hex8", 0.6, 1),
    );
    let (out, _) = common::run_case(&with_predictor, 1, &["-q"]);
    assert_eq!(
        common::converged_newton_its(&out).len(),
        1,
        "the step was cut"
    );
}

/// With no cuts allowed the same scene fails: one clear line, exit 1, and a summary that says
/// so (finished steps, none here, stay on disk).
#[test]
fn a_step_that_cannot_be_cut_fails_clearly() {
    let toml = common::uncuttable_crushed_block();
    let case = common::write_case("cut_block_fail", &toml);
    let out_dir = case.parent().unwrap().join("out");
    let out = common::run_raw(&case, 1, &out_dir, &["-q"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "stderr: {stderr}");
    assert!(
        lines[0].starts_with("mortar: error: solve:"),
        "{}",
        lines[0]
    );
    assert!(lines[0].contains("did not converge"), "{}", lines[0]);
    // Why, and what to change.
    assert!(
        lines[0].contains("an inverted element): more load steps (steps.count)"),
        "{}",
        lines[0]
    );
    let s = common::summary(&out_dir);
    assert_eq!(s["converged"], false);
    assert!(s["message"].as_str().unwrap().contains("inverted"));
    // Outputs describe the last converged state (here the initial one), not the failed iterate.
    let u_max = common::displacements(&out_dir)
        .iter()
        .flat_map(|r| r[3..].iter().map(|v| v.abs()))
        .fold(0.0, f64::max);
    assert_eq!(u_max, 0.0);
    // No step finished: no metric of the model's state (the undeformed one would pass for a
    // result), only the run's counts.
    let metrics = s["metrics"].as_object().unwrap();
    let names: Vec<&String> = metrics.keys().collect();
    assert_eq!(
        names,
        ["free_dofs", "max_newton_its", "total_newton_its"],
        "{metrics:?}"
    );
}

/// `steps.on_failure = "continue"`: a step Newton does not converge (here: one iteration
/// allowed on a finite-strain compression) is accepted, marked `converged = 0` in the history
/// and counted in the summary, and the run goes on to the end; with the default the same run
/// stops.
#[test]
fn unconverged_steps_are_accepted_and_recorded_on_request() {
    let base = common::with_step_option(&common::compressed_block("hex8", 0.2, 3), "max_cuts = 0")
        + "[newton]\nmax_it = 1\n";
    let strict = common::write_case("unconverged_strict", &base);
    let out = common::run_raw(&strict, 1, &strict.parent().unwrap().join("out"), &["-q"]);
    assert!(
        !out.status.success(),
        "one Newton iteration should not converge"
    );

    let toml = common::with_step_option(&base, "on_failure = \"continue\"");
    let case = common::write_case("unconverged_continue", &toml);
    let (out_dir, _) = common::run_case(&case, 1, &["-q"]);
    assert_eq!(common::metric(&out_dir, "unconverged_steps"), 3.0);
    let history = common::History::read(&out_dir);
    let col = history.column("converged");
    let flags: Vec<&str> = history
        .lines
        .iter()
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    assert_eq!(flags, ["0", "0", "0"]);
    let s = common::summary(&out_dir);
    // The full load was reached, but not by converged steps.
    assert_eq!(s["completed"], true);
    assert_eq!(s["converged"], false);
    assert_eq!(s["steps"].as_array().unwrap().len(), 3);
    assert!(s["steps"]
        .as_array()
        .unwrap()
        .iter()
        .all(|st| st["converged"] == false));
}
