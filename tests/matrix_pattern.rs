//! The contact's matrix pattern against a slide of more than the search margin per step, in
//! release mode: `cargo test --release --test matrix_pattern`.
//!
//! The pattern holds the pairs an evaluation finds at a step's start and at the predicted end
//! of the step (with `steps.predictor`, the default), and grows at a Newton iterate whose pairs
//! it does not hold. A step that slides farther than the search margin would otherwise pair
//! faces outside it, as would the iterates that stray from the two states, and PETSc would
//! reallocate the matrix's rows for those entries at every Newton iteration that finds new
//! ones. The progress line of a step counts both: the iterates at which the pattern grew, and
//! the entries outside it.

mod common;

/// The refinement family's level 1 (`cases/refinement/hex8_1.toml`) made a strip (lower
/// 16 x 6 x 2, upper 10 x 4 x 2 elements over a width of 0.5) and slid in 4 steps of 0.125, two
/// lower faces each (as the family's level 4 slides).
fn long_steps_slide() -> String {
    let path = common::cases_dir().join("refinement/hex8_1.toml");
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in [
        ("divisions = [12, 12, 12]", "divisions = [16, 6, 2]"),
        ("divisions = [8, 8, 8]", "divisions = [10, 4, 2]"),
        ("hi = [1.0, 1.0, 1.0]", "hi = [1.0, 0.5, 1.0]"),
        ("hi = [1.0, 1.0, 2.0]", "hi = [1.0, 0.5, 2.0]"),
        ("count = 20", "count = 5"),
        ("vtu_every = 5", "vtu_every = 0"),
    ] {
        assert!(text.contains(from), "{}: no `{from}`", path.display());
        text = text.replacen(from, to, 1);
    }
    text
}

/// `history.csv`'s `matrix_entries`, step by step.
fn stored_entries(out_dir: &std::path::Path) -> Vec<f64> {
    let history = common::History::read(out_dir);
    let entries = history.column("matrix_entries");
    history.rows().iter().map(|r| r[entries]).collect()
}

/// The progress lines (steps and cuts) that count tangent entries outside the matrix pattern.
fn lines_outside_the_pattern(stdout: &str) -> Vec<&str> {
    stdout
        .lines()
        .filter(|l| l.contains(" tangent entries outside the matrix pattern"))
        .collect()
}

/// With the predictor (the default) no step adds an entry outside the pattern, and it follows
/// the contact. Without the predictor the slide reaches past the start's pattern: the pattern
/// grows at Newton iterates instead, and no entry falls outside it either, on one rank or two
/// (where every rank must agree to grow it).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test matrix_pattern"
)]
fn a_slide_past_the_search_margin_stays_inside_the_pattern() {
    let predicted = long_steps_slide();
    let case = common::write_case("pattern_predicted", &predicted);
    let (out_dir, stdout) = common::run_case(&case, 1, &[]);
    assert_eq!(
        lines_outside_the_pattern(&stdout),
        Vec::<&str>::new(),
        "with the predictor"
    );
    // The pattern follows the contact: as the upper block slides past the lower one's end
    // the contact shrinks, and the couplings it left behind are dropped, so the matrix stores
    // fewer entries at the last step than at some step before (a pattern that kept every pair
    // of the slide's path would only grow: 3 % lower is about half of what the last steps
    // drop).
    let per_step = stored_entries(&out_dir);
    let most = per_step.iter().copied().fold(0.0, f64::max);
    assert!(
        per_step[per_step.len() - 1] < 0.97 * most,
        "stored entries per step {per_step:?}"
    );

    let unpredicted = common::with_step_option(&predicted, "predictor = false");
    let case = common::write_case("pattern_unpredicted", &unpredicted);
    for ranks in [1, 2] {
        let (_, stdout) = common::run_case(&case, ranks, &[]);
        assert_eq!(
            lines_outside_the_pattern(&stdout),
            Vec::<&str>::new(),
            "without the predictor, {ranks} rank(s)"
        );
        assert!(
            stdout.contains("matrix pattern grown at"),
            "without the predictor, {ranks} rank(s):\n{stdout}"
        );
    }
}
