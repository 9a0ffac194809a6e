//! The load-step predictor with the last Newton factorization
//! (`steps.predictor_tangent = "last_newton"`, the default) against the converged tangent
//! (`"converged"`): how often it factorizes (PETSc's count of `MatLUFactorNum` outside the
//! solver's stages in `-log_view`, where the predictor runs), on the frictional slide and after
//! cut steps, and the state it ends in.

mod common;

/// `steps.predictor_tangent = "last_newton"` (the default): the predictor solves with the last
/// step's last Newton factorization, so only the first step's predictor factorizes (PETSc's
/// count of `MatLUFactorNum` outside the solver's stages in `-log_view`, where the predictor
/// runs: one against one per step with `"converged"`; the test fails when the reuse is
/// dropped), and the run ends where the consistent predictor's does, within the Newton
/// tolerance, on 1 and 2 ranks.
#[test]
fn predictor_reusing_the_newton_factorization_factorizes_once() {
    let reuse = common::slide_case(5);
    let base = common::with_step_option(&reuse, "predictor_tangent = \"converged\"");
    assert_ne!(reuse, base);
    let run = |name: &str, text: &str, ranks: usize| {
        let case = common::write_case(&format!("{name}_{ranks}"), text);
        let (out, factorizations) = common::run_counting_predictor_factorizations(&case, ranks);
        let steps = common::converged_newton_its(&out).len();
        let cut = common::summary(&out)["steps"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["cut"] != 0);
        assert!(!cut, "{name}: a step was cut");
        (out, factorizations, steps)
    };
    let (consistent, count, steps) = run("predictor_converged", &base, 1);
    assert_eq!(
        count, steps,
        "converged tangent: one factorization per step"
    );
    let (reused, count, _) = run("predictor_last_newton", &reuse, 1);
    assert_eq!(
        count, 1,
        "last_newton: only the first step's predictor factorizes"
    );
    let (reused_2, count, _) = run("predictor_last_newton", &reuse, 2);
    assert_eq!(count, 1, "last_newton on 2 ranks");
    let apart = common::max_rel_difference_of_runs(&consistent, &reused);
    assert!(apart < 1e-7, "last_newton against converged: {apart:e}");
    let ranks = common::max_rel_difference_of_runs(&reused, &reused_2);
    assert!(ranks < 1e-8, "last_newton, 1 vs 2 ranks: {ranks:e}");
}

/// `steps.predictor_tangent = "last_newton"` after cut steps: a failed attempt leaves its own
/// factorization behind, so the predictor of every retry assembles the tangent again, and only
/// the predictor of a step after a converged one reuses the last Newton factorization. The
/// block compressed 60 % in one step with at most 2 Newton iterations per solve is cut many
/// times; the predictor factorizes (in `-log_view`'s main stage) once plus once per cut, against
/// once per attempt (steps plus cuts) with the converged tangent, and both end in the same
/// state.
#[test]
fn the_predictor_reuses_no_factorization_of_a_failed_attempt() {
    let base = common::compressed_block("hex8", 0.6, 1) + "[newton]\nmax_it = 2\n";
    let run = |name: &str, tangent: &str| {
        let text = common::with_step_option(&base, &format!("predictor_tangent = \"{tangent}\""));
        let case = common::write_case(name, &text);
        let (out, factorizations) = common::run_counting_predictor_factorizations(&case, 1);
        let steps = common::summary(&out)["steps"].as_array().unwrap().clone();
        let cuts: usize = steps
            .iter()
            .map(|s| s["cut"].as_u64().unwrap() as usize)
            .sum();
        assert!(cuts >= 2, "{name}: expected cut steps, {cuts}");
        (out, factorizations, steps.len(), cuts)
    };
    let (reused, count, _, cuts) = run("predictor_cuts_last_newton", "last_newton");
    assert_eq!(
        count,
        1 + cuts,
        "last_newton: the first step and every retry factorize"
    );
    let (consistent, count, steps, cuts) = run("predictor_cuts_converged", "converged");
    assert_eq!(count, steps + cuts, "converged: every attempt factorizes");
    let d = common::max_rel_difference_of_runs(&reused, &consistent);
    assert!(d < 1e-8, "last_newton against converged after cuts: {d:e}");
}
