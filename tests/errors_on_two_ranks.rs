//! Failures on 2 ranks (under `mpirun --timeout`): bad input, bad PETSc options, a failed step,
//! a write that fails on one rank, an output folder that cannot be made and a log that cannot
//! be written each end the job with one `mortar: error:` line ([`common::the_error_line`]),
//! never a hang; a failed step names the same element as on 1 rank.

mod common;

/// Bad input, bad PETSc options (also those read only at the first factorization) and a failed
/// solve on 2 ranks: one error line, exit non-zero, and no hang (mpirun's --timeout would give exit code 110).
#[test]
fn collective_failures_on_two_ranks_report_once() {
    let sphere = common::thick_sphere_case("hex8", 1);
    let bad_case = sphere.replace("young = 1000.0", "young = -1.0");
    let failing = common::uncuttable_crushed_block();
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
        let line = common::the_error_line(&out, name);
        assert!(line.contains(culprit), "{name}: {line}");
    }
}

/// A step that fails on inverted elements names the same element, with its det F, on 1 and on
/// 2 ranks: the lowest inverted element of all ranks.
#[test]
fn a_failed_step_names_the_same_element_on_one_and_two_ranks() {
    let failing = common::uncuttable_crushed_block();
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
/// file, and no hang (not a `[rank 1] ...` line and an abort of the job through MPI).
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
    let line = common::the_error_line(&out, "a rank-local write");
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
/// it, once, before any step.
#[test]
fn an_output_folder_that_cannot_be_made_is_reported_once() {
    let case = common::write_case("two_rank_out_file", &common::thick_sphere_case("hex8", 1));
    let out_file = case.parent().unwrap().join("results");
    std::fs::write(&out_file, "not a folder").unwrap();
    let out = common::run_raw(&case, 2, &out_file, &["-q"]);
    let line = common::the_error_line(&out, "--out a file");
    assert!(
        line.starts_with("mortar: error: output: ") && line.contains("two_rank_out_file/results"),
        "{line}"
    );
}

/// A `-log_view` file rank 0 cannot write fails inside `PetscFinalize` on that rank alone,
/// after the results are written, while the other rank waits in it: the job is aborted with
/// the reason instead of hanging, and the results stay on disk.
#[test]
fn an_unwritable_log_aborts_at_the_end_instead_of_hanging() {
    let case = common::write_case("two_rank_bad_log", &common::thick_sphere_case("hex8", 1));
    let out_dir = case.parent().unwrap().join("out");
    let blocker = case.parent().unwrap().join("not_a_folder");
    std::fs::write(&blocker, "a file").unwrap();
    let log = format!(":{}", blocker.join("log.txt").display());
    let out = common::run_raw(&case, 2, &out_dir, &["-q", "-log_view", &log]);
    let line = common::the_error_line(&out, "an unwritable log");
    assert!(line.contains("-log_view"), "{line}");
    assert!(out_dir.join("summary.json").is_file());
}
