//! The assembled tangent of frictional contact against PETSc's finite-difference Jacobian
//! (`-snes_test_jacobian`) at every Newton iterate of a sliding scene (`common::slide_case`),
//! for mortar contact (as it is, with the sides swapped, with fans of pallets) and for
//! node-on-segment contact (with its 1 against 2 ranks check).

mod common;

/// `||J - J_fd|| / ||J||` at every Newton iterate, from PETSc's `-snes_test_jacobian`.
fn jacobian_test_ratios(stdout: &str) -> Vec<f64> {
    stdout
        .lines()
        .filter_map(|l| l.split("||J - Jfd||_F/||J||_F = ").nth(1))
        .map(|r| r.split(',').next().unwrap().trim().parse().unwrap())
        .collect()
}

/// The assembled tangent (bulk, contact weights, normals, gap, slip, return map) is the
/// derivative of the assembled residual: PETSc's one-sided finite-difference Jacobian agrees to
/// its own accuracy at the iterates of every step, in stick and in slip. The residual is only
/// piecewise smooth (a node opens or closes, sticks or slips): where a finite-difference
/// perturbation of one dof crosses such a kink, that column differs by the jump, so the test
/// bounds the median (1e-7) and the share of iterates above 1e-4 (1 in 40, which the tie-break
/// of the Coulomb law, `contact::law::CONE_TIE`, keeps: at the start of a step round-off no
/// longer picks the tangent).
///
/// The bilateral iteration is off: its tangent of a node in tension is by design not the
/// derivative of its residual (docs/theory.md section 6).
///
/// Run three times: as the slide is (the small upper block's surface secondary, fully covered);
/// with the sides swapped, so that the lower surface's nodes under the upper block's edges are
/// partly covered: they carry the coverage scale of their penalties and, below 5 % coverage,
/// the fade of their traction, whose derivatives are then part of the tangent (the test fails
/// without either); and with the overlaps split into fans of pallets.
#[test]
fn contact_jacobian_matches_finite_differences() {
    for (name, text) in [
        ("contact_jacobian_fd", common::slide_case(5)),
        (
            "contact_jacobian_fd_partly_covered",
            common::swapped_slide_case(5),
        ),
        (
            "contact_jacobian_fd_fan",
            common::with_fan_pallets(&common::slide_case(5)),
        ),
    ] {
        let text = common::with_step_option(&text, "bilateral_iteration = false");
        let case = common::write_case(name, &text);
        jacobian_matches_finite_differences(&case);
    }
}

fn jacobian_matches_finite_differences(case: &std::path::Path) {
    let (out, stdout) = common::run_case(case, 1, &["-snes_test_jacobian"]);
    let ratios = jacobian_test_ratios(&stdout);
    assert!(
        ratios.len() >= 10,
        "too few Jacobian tests: {}",
        ratios.len()
    );
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let above = ratios.iter().filter(|&&r| r > 1e-4).count();
    assert!(
        median < 1e-7,
        "median ||J - Jfd|| / ||J|| = {median:e}; all: {ratios:?}"
    );
    assert!(
        above * 40 <= ratios.len(),
        "{above} of {} iterates above 1e-4: {ratios:?}",
        ratios.len()
    );
    // The slide reached slip: at its last step, tangential contact force at mu times the normal
    // force. (Not the mean `slip_force_ratio`: where the compression makes every node slip
    // outward in the first step, that step counts, with its small net tangential force.)
    let history = common::History::read(&out);
    let last = history.rows().pop().unwrap();
    let tangential = last[history.column("contact_slide_tangential")];
    let normal = last[history.column("contact_slide_normal")];
    let ratio = tangential / (common::SLIDE_FRICTION * normal);
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "last step: t / (mu n) = {ratio}"
    );
}

/// The same checks for node-on-segment contact on the same slide: the assembled tangent against
/// PETSc's finite-difference Jacobian (median below 1e-7, at most 1 iterate in 12 above 1e-4:
/// node-on-segment is only piecewise continuous, and where a node's closest point changes
/// segment the residual jumps, which no tangent can match), and 1 against 2 ranks (1e-8), with
/// friction and without. With friction, a node that slipped starts the next step with its trial
/// on the Coulomb cone: `contact::law::CONE_TIE` settles the tie (slip), so that round-off does
/// not pick its first tangent, stick or slip, differently on 1 and 2 ranks. Every solve runs to
/// `newton.rtol` (`augmented_rtol` as tight), so that the share of iterates sampled where the
/// residual jumps does not grow as the solves between augmentations stop early.
#[test]
fn node_on_segment_jacobian_and_ranks() {
    let text =
        common::with_node_on_segment(&common::slide_case(5)) + "[newton]\naugmented_rtol = 1e-10\n";
    assert!(text.contains("node_on_segment"));
    let case = common::write_case("nts_jacobian_fd", &text);
    let (_, stdout) = common::run_case(&case, 1, &["-snes_test_jacobian"]);
    let mut ratios = jacobian_test_ratios(&stdout);
    assert!(
        ratios.len() >= 10,
        "too few Jacobian tests: {}",
        ratios.len()
    );
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    let above = ratios.iter().filter(|&&r| r > 1e-4).count();
    assert!(median < 1e-7, "median {median:e}; all: {ratios:?}");
    assert!(above * 12 <= ratios.len(), "{above} above 1e-4: {ratios:?}");
    for (name, friction) in [("nts_ranks", "0.3"), ("nts_ranks_frictionless", "0.0")] {
        let case = common::write_case(
            name,
            &text.replace("friction = 0.3", &format!("friction = {friction}")),
        );
        let (one, _) = common::run_case(&case, 1, &["-q"]);
        let (two, _) = common::run_case(&case, 2, &["-q"]);
        let d = common::max_rel_difference_of_runs(&one, &two);
        assert!(d < 1e-8, "{name}: 1 vs 2 ranks: {d:e}");
    }
}
