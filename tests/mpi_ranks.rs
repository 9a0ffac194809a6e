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
