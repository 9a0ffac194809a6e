//! Expectations of a case (`expect`): printed with their measured values, and a run whose
//! expectation fails exits with one error line naming it, on 1 and 2 ranks.

mod common;

/// Expectations (`expect`): printed with their measured values; a run whose expectation fails
/// exits with one error line naming it.
#[test]
fn expectations_are_printed_and_enforced() {
    let base = common::compressed_block("hex8", 0.05, 2);
    let good = common::write_case(
        "expect_good",
        &format!("expect = [\"max_newton_its >= 1\", \"total_newton_its > 0\"]\n{base}"),
    );
    let (_, stdout) = common::run_case(&good, 1, &[]);
    assert_eq!(stdout.matches("-> ok").count(), 2, "{stdout}");

    let bad = common::write_case(
        "expect_bad",
        &format!("expect = [\"max_newton_its <= 0\"]\n{base}"),
    );
    // On 1 and on 2 ranks: printed once, one error line, no MPI abort.
    for ranks in [1, 2] {
        let out = common::run_raw(&bad, ranks, &bad.parent().unwrap().join("out"), &["-q"]);
        assert!(!out.status.success());
        let stdout = String::from_utf8_lossy(&out.stdout);
        let printed = stdout
            .matches("expect max_newton_its <= 0: max_newton_its = ")
            .count();
        assert_eq!(printed, 1, "{stdout}");
        assert!(stdout.contains("-> FAILED"), "{stdout}");
        // (mpirun adds its own banner about the non-zero exit.)
        let stderr = String::from_utf8_lossy(&out.stderr);
        let ours: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("mortar:"))
            .collect();
        assert_eq!(
            ours,
            ["mortar: error: expect: 1 of 1 expectation(s) failed: max_newton_its <= 0"],
            "{ranks} rank(s): {stderr}"
        );
        assert!(!stderr.contains("MPI_ABORT"), "{stderr}");
    }
}
