//! The linear solver of the Newton steps (`newton.linear_solver`, `newton.direct_below`).
//!
//! - The automatic choice: the frictional slide of `common::slide_case` solved directly below
//!   the crossover and iteratively from it on, as its first lines say; both converge to the same
//!   state.
//! - The iterative path sets its multigrid up once per load step, not per Newton iteration.
//! - The iterative path on the smallest level of the refinement family
//!   (`cases/refinement/hex8_1.toml`, 8 028 free dofs; release mode:
//!   `cargo test --release --test linear_solver`): GMRES with an exact solve on the interface's
//!   dofs and multigrid on the rest converges every load step with at most
//!   [`MAX_LINEAR_PER_NEWTON`] linear iterations per Newton iteration (inexact Newton: each
//!   linear tolerance follows the Newton residual's progress) and at most
//!   [`MAX_NEWTON_ITERATIVE_OVER_DIRECT`] times the direct solve's Newton iterations, to the
//!   direct solve's state within the Newton tolerance (1e-8 relative), and to the same state
//!   on 1 and 2 ranks; the direct solve takes
//!   at most [`MAX_NEWTON_LEVEL_1`] Newton iterations, and no run cuts a step.
//! - The interface coarse correction (`newton.coarse_correction`) on the smallest level: the
//!   split's state (within [`MOST_STATE_DIFFERENCE_COARSE`]) in at most
//!   [`MAX_LINEAR_PER_NEWTON_COARSE`] GMRES iterations per Newton
//!   iteration, at most [`MOST_LINEAR_COARSE_OVER_SPLIT`] of the split's, on 1 and 2 ranks
//!   alike (release mode).
//! - The blocks stay in contact while they slide: the normal contact force of every slide step
//!   lies between [`LEAST_SLIDE_FORCE`] and 1 times that at the end of the compression (it
//!   falls as the upper block leaves the lower one; an earlier code lost the contact in the
//!   slide's fourth step and slid the blocks through each other with no force).

mod common;

use std::path::PathBuf;

/// The bound on the linear iterations per Newton iteration of any step of the smallest level
/// (issue 29's target: 40). Measured with inexact Newton: 11-18 on 1 rank; 26-37 with the fixed
/// linear tolerance, 51-55 in the slide while the bulk's multigrid kept the interpolation of
/// its first set-up (docs/performance.md, "Refinement" and "Inexact Newton").
const MAX_LINEAR_PER_NEWTON: f64 = 25.0;

/// The most Newton iterations of the iterative path, as a multiple of the direct solve's:
/// inexact Newton's rough early steps cost a few (measured 336 on 1 rank against 319 before
/// the bilateral iteration and the loose solves between augmentations).
const MAX_NEWTON_ITERATIVE_OVER_DIRECT: f64 = 1.1;

/// The bound on the Newton iterations of the smallest level's run with the direct solve:
/// measured 165 without a cut (6-12 per slide step); 239 with every solve to `newton.rtol`,
/// 319 without the bilateral iteration either, 363 while every slide step first tried full
/// Newton steps (docs/performance.md, "Newton on frictional contact").
const MAX_NEWTON_LEVEL_1: f64 = 190.0;

/// The least normal contact force of a slide step, in units of that at the end of the
/// compression (measured: 0.609 in the last step, where half the upper block overhangs).
const LEAST_SLIDE_FORCE: f64 = 0.55;

/// Load steps of the compression (the first fifth of the load in 20 steps).
const COMPRESSION_STEPS: usize = 4;

/// `text` with `settings` in its `[newton]` section (the case has none).
fn with_newton(text: &str, settings: &str) -> String {
    text.replace("[steps]", &format!("[newton]\n{settings}\n[steps]"))
}

/// The case `text` written into a fresh folder named `name`.
fn case(name: &str, text: &str) -> PathBuf {
    common::write_case(name, text)
}

#[test]
fn auto_solves_directly_below_the_crossover_and_iteratively_from_it() {
    let slide = common::slide_case(4);
    let below = case(
        "auto_direct",
        &with_newton(&slide, "direct_below = 1000000"),
    );
    let above = case("auto_iterative", &with_newton(&slide, "direct_below = 1"));
    let (direct, printed) = common::run_case(&below, 1, &[]);
    assert!(
        printed.contains("linear solver: direct (LU through MUMPS): "),
        "{printed}"
    );
    let (iterative, printed) = common::run_case(&above, 1, &[]);
    assert!(
        printed.contains("linear solver: iterative (GMRES; an exact solve on the interfaces'"),
        "{printed}"
    );
    let d = common::max_rel_difference_of_runs(&direct, &iterative);
    assert!(d < 1e-8, "iterative against direct: {d:e}");
}

/// The calls of a PETSc event (the first number of its line) in the stage `stage` of a
/// `-log_view` report; 0 when the stage does not list it.
fn event_count(log_view: &str, stage: &str, event: &str) -> usize {
    log_view
        .lines()
        .skip_while(|l| !(l.starts_with("--- Event Stage") && l.ends_with(&format!(": {stage}"))))
        .skip(1)
        .take_while(|l| !l.starts_with("--- Event Stage"))
        .find_map(|l| {
            let mut fields = l.split_whitespace();
            (fields.next() == Some(event)).then(|| fields.next().unwrap().parse().unwrap())
        })
        .unwrap_or(0)
}

/// The iterative path sets the bulk's multigrid up once per load step, at its first Newton
/// iteration, and keeps it whole through the step's other Newton iterations and Uzawa
/// augmentations (PETSc's `PCSetUp_GAMG+` event in the `solve` stage), where the interface's
/// factorization is redone at every Newton iteration.
#[test]
fn the_multigrid_is_set_up_once_per_load_step() {
    let slide = case(
        "multigrid_per_step",
        &with_newton(&common::slide_case(4), "direct_below = 1"),
    );
    let (out, log_view) = common::run_case(&slide, 1, &["-q", "-log_view"]);
    let history = common::History::read(&out);
    let newton = history.column("newton_its");
    let newton: Vec<f64> = history.rows().iter().map(|r| r[newton]).collect();
    let steps_solved = newton.iter().filter(|&&n| n > 0.0).count();
    let newton_its: f64 = newton.iter().sum();
    assert!(
        newton_its as usize > 2 * steps_solved,
        "{newton_its} Newton iterations in {steps_solved} steps: too few to tell"
    );
    let set_ups = event_count(&log_view, "solve", "PCSetUp_GAMG+");
    assert_eq!(
        set_ups, steps_solved,
        "multigrid set-ups in the solves, against the steps that took a Newton iteration \
         ({newton_its} Newton iterations)"
    );
}

/// A composite preconditioner whose first part is a field split (the split, then multigrid on
/// the whole matrix) gets the interface's fields, and solves the frictional slide to the
/// direct solve's state, on 1 and 2 ranks.
#[test]
fn a_composite_preconditioner_gets_the_interface_fields() {
    let case = case("composite_split", &common::slide_case(4));
    let (direct, _) = common::run_case(&case, 1, &["-q"]);
    let composite = [
        "-q",
        "-ksp_type",
        "gmres",
        "-ksp_rtol",
        "1e-10",
        "-pc_type",
        "composite",
        "-pc_composite_type",
        "multiplicative",
        "-pc_composite_pcs",
        "fieldsplit,gamg",
        "-sub_0_fieldsplit_interface_pc_type",
        "lu",
        "-sub_0_fieldsplit_bulk_pc_type",
        "jacobi",
    ];
    for ranks in [1, 2] {
        let (out, _) = common::run_case(&case, ranks, &composite);
        let d = common::max_rel_difference_of_runs(&direct, &out);
        assert!(d < 1e-8, "{ranks} rank(s): {d:e} from the direct solve");
    }
}

/// The bound on the GMRES iterations per Newton iteration over the smallest level's run with
/// the interface coarse correction (`newton.coarse_correction`): measured 8.5 (1 311 in 154)
/// on 1 rank and 8.4 (1 301 in 154) on 2, where the split alone takes 11.3 (1 684 in 149).
const MAX_LINEAR_PER_NEWTON_COARSE: f64 = 9.5;

/// The most GMRES iterations of the smallest level's run with the coarse correction, as a
/// fraction of those of the split alone on 1 rank (measured 0.78 on 1 rank, 0.77 on 2).
const MOST_LINEAR_COARSE_OVER_SPLIT: f64 = 0.85;

/// How far the end states of the smallest level's runs with the coarse correction may lie from
/// the split's and from each other, relative to the largest displacement. Each run stops at
/// the Newton tolerance, where its last iterate falls: the split's last residual 1.1e-10, the
/// correction's 7.2e-10 on either rank count, so their states differ by more than the split's
/// runs do among themselves (measured 8.9e-9 and 1.3e-9 from the split on 1 and 2 ranks, 1.0e-8
/// between 1 and 2 ranks).
const MOST_STATE_DIFFERENCE_COARSE: f64 = 3e-8;

/// The interface coarse correction after the split (`newton.coarse_correction`) solves the
/// smallest level to the split's state (within [`MOST_STATE_DIFFERENCE_COARSE`]) on 1 and 2
/// ranks, in fewer GMRES iterations, through the slide (where the matrix is made anew as the
/// contact pattern grows: a composite preconditioner's parts must get the new matrix).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test linear_solver"
)]
fn the_coarse_correction_solves_the_smallest_level_in_fewer_linear_iterations() {
    let level = common::scene_dir("refinement").join("hex8_1.toml");
    let text = std::fs::read_to_string(&level).unwrap();
    let split = case(
        "level1_split",
        &with_newton(
            &text,
            "linear_solver = \"iterative\"\ncoarse_correction = false",
        ),
    );
    let coarse = case(
        "level1_coarse",
        &with_newton(
            &text,
            "linear_solver = \"iterative\"\ncoarse_correction = true",
        ),
    );
    let (split_out, _) = common::run_case(&split, 1, &["-q"]);
    let linear = |out: &std::path::Path| common::History::read(out).sum("linear_its");
    let split_linear = linear(&split_out);
    let (coarse1, printed) = common::run_case(&coarse, 1, &[]);
    assert!(
        printed.contains("then a coarse correction across the interfaces"),
        "{printed}"
    );
    let (coarse2, _) = common::run_case(&coarse, 2, &["-q"]);
    for (out, ranks) in [(&coarse1, 1), (&coarse2, 2)] {
        let history = common::History::read(out);
        assert_eq!(history.sum("cuts"), 0.0, "{ranks} rank(s): a step was cut");
        let (newton, linear) = (common::metric(out, "total_newton_its"), linear(out));
        assert!(
            linear <= MAX_LINEAR_PER_NEWTON_COARSE * newton,
            "{ranks} rank(s): {linear} GMRES iterations in {newton} Newton iterations"
        );
        assert!(
            linear <= MOST_LINEAR_COARSE_OVER_SPLIT * split_linear,
            "{ranks} rank(s): {linear} GMRES iterations against the split's {split_linear}"
        );
        let d = common::max_rel_difference_of_runs(&split_out, out);
        assert!(
            d < MOST_STATE_DIFFERENCE_COARSE,
            "{ranks} rank(s) against the split alone: {d:e}"
        );
    }
    let d = common::max_rel_difference_of_runs(&coarse1, &coarse2);
    assert!(d < MOST_STATE_DIFFERENCE_COARSE, "1 against 2 ranks: {d:e}");
}

/// Linear iterations per Newton iteration of every step of a run (steps without a Newton
/// iteration left out).
fn linear_per_newton(out: &std::path::Path) -> Vec<f64> {
    let history = common::History::read(out);
    let (newton, linear) = (history.column("newton_its"), history.column("linear_its"));
    history
        .rows()
        .iter()
        .filter(|r| r[newton] > 0.0)
        .map(|r| r[linear] / r[newton])
        .collect()
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release --test linear_solver"
)]
fn the_iterative_path_solves_the_smallest_level_as_the_direct_one() {
    let level = common::scene_dir("refinement").join("hex8_1.toml");
    let text = std::fs::read_to_string(&level).unwrap();
    let direct = case(
        "level1_direct",
        &with_newton(&text, "linear_solver = \"direct\""),
    );
    let iterative = case(
        "level1_iterative",
        &with_newton(
            &text,
            "linear_solver = \"iterative\"\ncoarse_correction = false",
        ),
    );
    let (direct_out, _) = common::run_case(&direct, 1, &["-q"]);
    let newton_direct = common::metric(&direct_out, "total_newton_its");
    assert!(
        newton_direct <= MAX_NEWTON_LEVEL_1,
        "{newton_direct} Newton iterations with the direct solve"
    );
    let (iter1, _) = common::run_case(&iterative, 1, &["-q"]);
    let (iter2, _) = common::run_case(&iterative, 2, &["-q"]);
    for out in [&direct_out, &iter1, &iter2] {
        let history = common::History::read(out);
        let cuts = history.sum("cuts");
        assert_eq!(cuts, 0.0, "{}: {cuts} step cut(s)", out.display());
        let normal = history.column("contact_blocks_normal");
        let forces: Vec<f64> = history.rows().iter().map(|r| r[normal]).collect();
        let pressed = forces[COMPRESSION_STEPS - 1];
        for (k, f) in forces.iter().enumerate().skip(COMPRESSION_STEPS) {
            assert!(
                (LEAST_SLIDE_FORCE * pressed..=pressed).contains(f),
                "{}: step {}: normal contact force {f} against {pressed} pressed",
                out.display(),
                k + 1
            );
        }
    }
    for (out, ranks) in [(&iter1, 1), (&iter2, 2)] {
        let per_newton = linear_per_newton(out);
        let most = per_newton.iter().copied().fold(0.0, f64::max);
        assert!(
            most <= MAX_LINEAR_PER_NEWTON,
            "{ranks} rank(s): {most} linear iterations per Newton iteration ({per_newton:?})"
        );
        let newton = common::metric(out, "total_newton_its");
        assert!(
            newton <= MAX_NEWTON_ITERATIVE_OVER_DIRECT * newton_direct,
            "{ranks} rank(s): {newton} Newton iterations against {newton_direct} (direct)"
        );
        let d = common::max_rel_difference_of_runs(&direct_out, out);
        assert!(d < 1e-8, "{ranks} rank(s) against the direct solve: {d:e}");
    }
    let d = common::max_rel_difference_of_runs(&iter1, &iter2);
    assert!(d < 1e-8, "1 against 2 ranks: {d:e}");
}
