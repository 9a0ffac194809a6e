//! The same scene on 1 and 2 ranks (under `mpirun --timeout`) gives the same answer.
//!
//! Goal (DEVELOPERS.md): results equal to ~1e-10 relative. With the default direct solver the two
//! runs differ only by round-off in a different summation order.

mod common;

/// Lamé sphere, Hex20, linear: displacements and the energy error agree.
#[test]
fn thick_sphere_one_and_two_ranks_agree() {
    let case = common::write_case("ranks_sphere", &common::thick_sphere_case("hex20", 3));
    let (out1, _) = common::run_case(&case, 1, &["-q"]);
    let (out2, _) = common::run_case(&case, 2, &["-q"]);
    let d =
        common::max_rel_difference(&common::displacements(&out1), &common::displacements(&out2));
    assert!(d < 1e-10, "1 vs 2 ranks: max relative difference {d:e}");
    let (e1, e2) = (
        common::metric(&out1, "energy_error"),
        common::metric(&out2, "energy_error"),
    );
    assert!((e1 - e2).abs() < 1e-10 * e1, "energy error {e1} vs {e2}");
    assert_eq!(common::summary(&out2)["ranks"], 2);
    // Both ranks wrote a piece.
    assert!(out2.join("vtu/thick_sphere_0001_r1.vtu").is_file());
}

/// A finite-strain scene with several steps: Newton's path depends on round-off only.
#[test]
fn compressed_block_one_and_two_ranks_agree() {
    let case = common::write_case("ranks_block", &common::compressed_block("hex20", 0.3, 4));
    let (out1, _) = common::run_case(&case, 1, &["-q"]);
    let (out2, _) = common::run_case(&case, 2, &["-q"]);
    let d =
        common::max_rel_difference(&common::displacements(&out1), &common::displacements(&out2));
    assert!(d < 1e-10, "1 vs 2 ranks: max relative difference {d:e}");
}

/// The one `mortar: error:` line of a failed run's stderr (mpirun adds its own banners around
/// it); `what` names the run in the messages. Fails unless the run failed without timing out
/// (mpirun's `--timeout` gives exit code 110) and printed exactly one such line.
fn the_error_line(out: &std::process::Output, what: &str) -> String {
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

/// SIGTERM to one rank of two stops both at the same point (they poll the signal together,
/// here inside a Newton solve: the steps take several iterations): exit status 143, one line,
/// and rank 0's summary and history with the steps finished.
#[test]
fn a_signal_to_one_rank_stops_both() {
    let case = common::write_case("interrupted_two_ranks", &common::slide_case(100));
    let out_dir = case.parent().unwrap().join("out");
    let run = common::subcommand("run", &case, 2, &out_dir, &[]);
    let out = common::run_and_signal(run, "  step 2 ", "TERM", 1);
    let line = the_error_line(&out, "SIGTERM to rank 1");
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

/// Bad input, bad PETSc options (also those read only at the first factorization) and a failed
/// solve on 2 ranks: one error line, exit non-zero, and no hang (mpirun's --timeout would give exit code 110).
#[test]
fn collective_failures_on_two_ranks_report_once() {
    let sphere = common::thick_sphere_case("hex8", 1);
    let bad_case = sphere.replace("young = 1000.0", "young = -1.0");
    let failing = common::compressed_block_no_predictor("hex8", 0.6, 1)
        .replace("count = 1", "count = 1\nmax_cuts = 0");
    let runs: [(&str, String, &[&str], &str); 5] = [
        ("two_rank_bad_case", bad_case, &["-q"], "young"),
        (
            "two_rank_bad_option",
            sphere.clone(),
            &["-q", "-ksp_type", "nonsense"],
            "nonsense",
        ),
        // Options PETSc reads only at the first factorization: checked before the first step
        // (`ksp::probe_factorization`), not met by each rank in a solve.
        (
            "two_rank_missing_solver_package",
            sphere.clone(),
            &["-q", "-pc_factor_mat_solver_type", "nonexistent"],
            "nonexistent",
        ),
        (
            "two_rank_bad_package_option",
            sphere,
            &["-q", "-mat_mumps_icntl_8", "xyz"],
            "-mat_mumps_icntl_8 xyz",
        ),
        (
            "two_rank_failed_solve",
            failing,
            &["-q"],
            "did not converge",
        ),
    ];
    for (name, toml, args, culprit) in runs {
        let case = common::write_case(name, &toml);
        let out_dir = case.parent().unwrap().join("out");
        let out = common::run_raw(&case, 2, &out_dir, args);
        let line = the_error_line(&out, name);
        assert!(line.contains(culprit), "{name}: {line}");
    }
}

/// A step that fails on inverted elements names the same element, with its det F, on 1 and on
/// 2 ranks: the lowest inverted element of all ranks (each rank used to name its own first,
/// and 2 ranks the larger of the two, some without det F: "on another rank").
#[test]
fn a_failed_step_names_the_same_element_on_one_and_two_ranks() {
    let failing = common::compressed_block_no_predictor("hex8", 0.6, 1)
        .replace("count = 1", "count = 1\nmax_cuts = 0");
    let case = common::write_case("inverted_on_ranks", &failing);
    let messages: Vec<String> = [1, 2]
        .iter()
        .map(|&ranks| {
            let out_dir = case.parent().unwrap().join(format!("out_{ranks}"));
            let out = common::run_raw(&case, ranks, &out_dir, &["-q"]);
            assert_ne!(out.status.code(), Some(0));
            let s = common::summary(&out_dir);
            s["message"].as_str().unwrap().to_string()
        })
        .collect();
    assert!(
        messages[0].contains("inverted (det F = "),
        "{}",
        messages[0]
    );
    assert_eq!(messages[0], messages[1]);
}

/// A write that fails on one rank only (its VTU piece's path is a directory) is agreed on by
/// the ranks at the end of the step's output (`solver::results`): one error line, naming the
/// file, and no hang (it used to print `[rank 1] ...` and abort the job through MPI).
#[test]
fn a_rank_local_write_failure_is_reported_once() {
    let case = common::write_case(
        "two_rank_local_error",
        &common::thick_sphere_case("hex8", 2),
    );
    let out_dir = case.parent().unwrap().join("out");
    std::fs::create_dir_all(out_dir.join("vtu/thick_sphere_0001_r1.vtu/blocker")).unwrap();
    let t = std::time::Instant::now();
    let out = common::run_raw(&case, 2, &out_dir, &["-q"]);
    let line = the_error_line(&out, "a rank-local write");
    // Well inside mpirun's `--timeout` of 300 s, with room for a loaded CI host.
    let secs = t.elapsed().as_secs();
    assert!(secs < 150, "took {secs} s");
    assert!(
        line.starts_with("mortar: error: output: ") && line.contains("thick_sphere_0001_r1.vtu"),
        "{line}"
    );
    // The summary (rank 0's, written) says the same.
    let s = common::summary(&out_dir);
    assert_eq!(
        s["message"].as_str().map(|m| format!("mortar: error: {m}")),
        Some(line),
        "{s}"
    );
}

/// An output folder that cannot be made (`--out` names a file) on 2 ranks: one line naming
/// it, before any step (it used to come from each rank, after the whole set-up).
#[test]
fn an_output_folder_that_cannot_be_made_is_reported_once() {
    let case = common::write_case("two_rank_out_file", &common::thick_sphere_case("hex8", 1));
    let out_file = case.parent().unwrap().join("results");
    std::fs::write(&out_file, "not a folder").unwrap();
    let out = common::run_raw(&case, 2, &out_file, &["-q"]);
    let line = the_error_line(&out, "--out a file");
    assert!(
        line.starts_with("mortar: error: output: ") && line.contains("two_rank_out_file/results"),
        "{line}"
    );
}

/// A `-log_view` file rank 0 cannot write fails inside `PetscFinalize` on that rank alone,
/// after the results are written, while the other rank waits in it: the job is aborted with
/// the reason (it used to hang) and the results stay on disk.
#[test]
fn an_unwritable_log_aborts_at_the_end_instead_of_hanging() {
    let case = common::write_case("two_rank_bad_log", &common::thick_sphere_case("hex8", 1));
    let out_dir = case.parent().unwrap().join("out");
    let blocker = case.parent().unwrap().join("not_a_folder");
    std::fs::write(&blocker, "a file").unwrap();
    let log = format!(":{}", blocker.join("log.txt").display());
    let out = common::run_raw(&case, 2, &out_dir, &["-q", "-log_view", &log]);
    let line = the_error_line(&out, "an unwritable log");
    assert!(line.contains("-log_view"), "{line}");
    assert!(out_dir.join("summary.json").is_file());
}
