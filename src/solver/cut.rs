//! Step cutting: a load step whose solve fails is restored and halved (the size it took, which
//! the end of the load may clamp), at most `steps.max_cuts` times in a row and never below
//! `1 / (steps.count 2^max_cuts)`; after a converged cut step the step size doubles back toward
//! the nominal one.

/// What stops a failed step from being cut again.
#[derive(Debug, PartialEq)]
pub(super) enum CutLimit {
    /// `steps.max_cuts` cuts in a row.
    CutsInRow,
    /// The step is the nominal one halved `max_cuts` times: bounded in depth, not only in a
    /// row, so that fail and converge cycles cannot shrink it further.
    SmallestStep,
}

/// The limit a failed step of size `dt` meets after `cuts_in_row` cuts in a row (`dt_min`: the
/// smallest step allowed, a hair below the nominal one halved `max_cuts` times), if any.
pub(super) fn cut_limit(
    cuts_in_row: usize,
    max_cuts: usize,
    dt: f64,
    dt_min: f64,
) -> Option<CutLimit> {
    if cuts_in_row + 1 > max_cuts {
        Some(CutLimit::CutsInRow)
    } else if 0.5 * dt < dt_min {
        Some(CutLimit::SmallestStep)
    } else {
        None
    }
}

/// The limit in words, for the progress line and the summary's message.
pub(super) fn describe(limit: &CutLimit, dt: f64, max_cuts: usize) -> String {
    match limit {
        CutLimit::CutsInRow => format!("no cuts left ({max_cuts} allowed)"),
        CutLimit::SmallestStep => format!(
            "the step ({dt:.3e} of the load) is the smallest allowed (steps.max_cuts = \
             {max_cuts})"
        ),
    }
}

/// Why a solve that ended a run failed, and what in the case file to change, for its last line
/// (`reason`: PETSc's converged reason; `domain_error`: the solve met an unusable state).
pub(super) fn what_to_change(reason: &str, domain_error: bool) -> &'static str {
    match reason {
        _ if domain_error => {
            "an iterate left the domain (an inverted element): more load steps \
                              (steps.count) or more cuts (steps.max_cuts)"
        }
        "DIVERGED_MAX_IT" => {
            "Newton did not reach newton.atol or newton.rtol within \
                              newton.max_it iterations: more load steps (steps.count), a larger \
                              newton.max_it, or a smaller penalty"
        }
        "DIVERGED_LINE_SEARCH" => {
            "the line search found no decrease of the residual: more load \
                                   steps (steps.count) or a smaller penalty"
        }
        "DIVERGED_DTOL" => {
            "the residual grew or cycled between contact states: more load steps \
                            (steps.count) or a smaller penalty"
        }
        "DIVERGED_LINEAR_SOLVE" => {
            "the linear solve failed: newton.linear_solver = \"direct\", \
                                    or constrain a body left free to move"
        }
        "DIVERGED_FNORM_NAN" => {
            "the residual is not finite: more load steps (steps.count), or \
                                 check the material constants and loads"
        }
        _ => "more load steps (steps.count) or more cuts (steps.max_cuts)",
    }
}

#[cfg(test)]
mod tests {
    use super::{cut_limit, what_to_change, CutLimit};

    /// Each failure names what to change, the domain error first whatever PETSc's reason.
    #[test]
    fn a_failure_says_what_to_change() {
        assert!(what_to_change("DIVERGED_MAX_IT", false).contains("newton.max_it"));
        assert!(what_to_change("DIVERGED_LINE_SEARCH", false).contains("line search"));
        assert!(what_to_change("DIVERGED_LINEAR_SOLVE", false).contains("linear_solver"));
        assert!(what_to_change("DIVERGED_MAX_IT", true).contains("inverted"));
        assert!(what_to_change("DIVERGED_TR_DELTA", false).contains("steps.count"));
    }

    /// `steps.max_cuts = 2`, nominal step 0.01: a step cut twice in a row has no cut left; a
    /// step at a quarter of the nominal one after one cut in a row (cut twice before, then
    /// converged and grown back by one doubling) is at the smallest size instead (the sliding
    /// blocks' case 5 of Figure 7 ends so).
    #[test]
    fn a_failed_step_meets_the_limit_it_reached() {
        let (nominal, max_cuts) = (0.01, 2);
        let dt_min = nominal * 0.25 * (1.0 - 1e-12);
        let limit = |cuts, dt| cut_limit(cuts, max_cuts, dt, dt_min);
        assert_eq!(limit(0, nominal), None);
        assert_eq!(limit(1, nominal / 2.0), None);
        assert_eq!(limit(2, nominal / 4.0), Some(CutLimit::CutsInRow));
        assert_eq!(limit(2, nominal), Some(CutLimit::CutsInRow));
        assert_eq!(limit(1, nominal / 4.0), Some(CutLimit::SmallestStep));
        assert_eq!(limit(0, nominal / 4.0), Some(CutLimit::SmallestStep));
        assert_eq!(cut_limit(0, 0, nominal, nominal), Some(CutLimit::CutsInRow));
    }
}
