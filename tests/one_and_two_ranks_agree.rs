//! The same scene on 1 and 2 ranks (under `mpirun --timeout`) gives the same answer: the Lamé
//! sphere, a finite-strain block, and the frictional slide (also with its sides swapped).
//!
//! Goal: results equal to ~1e-10 relative. With the default direct solver the two runs differ
//! only by round-off in a different summation order. The frictional slide is held to 1e-8.

mod common;

/// Lamé sphere, Hex20, linear: displacements and the energy error agree.
#[test]
fn thick_sphere_one_and_two_ranks_agree() {
    let case = common::write_case("ranks_sphere", &common::thick_sphere_case("hex20", 3));
    let (out1, _) = common::run_case(&case, 1, &["-q"]);
    let (out2, _) = common::run_case(&case, 2, &["-q"]);
    let d = common::max_rel_difference_of_runs(&out1, &out2);
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
    let d = common::max_rel_difference_of_runs(&out1, &out2);
    assert!(d < 1e-10, "1 vs 2 ranks: max relative difference {d:e}");
}

/// 1 and 2 ranks give the same frictional slide (displacements to 1e-8 relative), also with
/// the sides swapped (partly covered secondary nodes, some fading out), and the same
/// segment-pair and quadrature-point counts (the test fails when every rank counts the faces it
/// integrates). With the sides swapped the contact zone moves over the secondary surface, and
/// the 2-rank deal of its nodes by work moves with it: a node changes rank between steps, its
/// multipliers and history handed over (the test fails when they are not). Nodes whose trial
/// starts a step on the Coulomb cone take the first tangent `contact::law::CONE_TIE` settles,
/// not one round-off picks on one rank count only.
#[test]
fn contact_one_and_two_ranks_agree() {
    for (name, text) in [
        ("contact_ranks", common::slide_case(5)),
        (
            "contact_ranks_partly_covered",
            common::swapped_slide_case(5),
        ),
    ] {
        let case = common::write_case(name, &text);
        let (one, _) = common::run_case(&case, 1, &["-q"]);
        let (two, _) = common::run_case(&case, 2, &["-q"]);
        let d = common::max_rel_difference_of_runs(&one, &two);
        assert!(d < 1e-8, "{name}: 1 vs 2 ranks: {d:e}");
        // The segment-pair counts of the last evaluation, summed over ranks, are the same: a
        // face next to a strip cut is integrated by both neighbours but counted by one.
        for kind in ["pairs_integrated", "no_overlap", "quadrature_points"] {
            let key = format!("pairs_slide_{kind}");
            let (a, b) = (common::metric(&one, &key), common::metric(&two, &key));
            assert!(a > 0.0 && a == b, "{name}: {key} {a} on 1 rank, {b} on 2");
        }
        // Each rank's contact seconds, for the balance `mortar family` reports.
        for (dir, ranks) in [(&one, 1), (&two, 2)] {
            let seconds = common::summary(dir)["contact_seconds_per_rank"].clone();
            let seconds = seconds.as_array().unwrap().clone();
            assert_eq!(seconds.len(), ranks, "{name}: {seconds:?}");
            assert!(
                seconds.iter().all(|s| s.as_f64().unwrap() > 0.0),
                "{name} on {ranks} rank(s): {seconds:?}"
            );
        }
    }
}
