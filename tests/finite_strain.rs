//! Finite strain: Newton converges quadratically with the consistent tangent.
//!
//! Scene: a Neo-Hookean cube (E = 100, nu = 0.3), compressed by 30 % along z in 6 steps, with
//! symmetry planes on three faces and lateral expansion free; and a cantilever (Neo-Hookean)
//! bent by a follower pressure on its top face.
//!
//! Passing: at most 8 Newton iterations per step with the default settings; the convergence
//! order estimated from the last three residuals above round-off, log(r3 / r2) / log(r2 / r1),
//! is at least 1.8 in every step, measured with the load-step predictor off (with it, Newton
//! needs only 2-4 iterations, too few above round-off for an order estimate);
//! the z-reaction equals the analytic homogeneous-compression force (below); and the summary's
//! `max_displacement` is the largest nodal displacement of `displacement.csv`, on 1 and 2
//! ranks. The compression force: for uniaxial stress
//! with free lateral faces the deformation is homogeneous, F = diag(s, s, 0.7), with s from
//! P_xx = 0 and the force P_zz x (reference area 1).

mod common;

/// Estimated convergence orders of every solve (only where three residuals lie above 1e-9 of
/// the first one, so round-off does not pollute the estimate).
fn orders(histories: &[Vec<f64>]) -> Vec<f64> {
    histories
        .iter()
        .filter_map(|h| {
            let floor = 1e-9 * h[0];
            let r: Vec<f64> = h.iter().copied().filter(|&v| v > floor).collect();
            (r.len() >= 3).then(|| {
                let n = r.len();
                (r[n - 1] / r[n - 2]).ln() / (r[n - 2] / r[n - 3]).ln()
            })
        })
        .collect()
}

#[test]
fn compressed_block_converges_quadratically() {
    for el in ["hex8", "hex20"] {
        // Defaults (with the load-step predictor): few iterations, no cut.
        let case = common::write_case(
            &format!("finite_block_{el}"),
            &common::compressed_block(el, 0.3, 6),
        );
        let (out, _) = common::run_case(&case, 1, &["-q"]);
        let its = common::converged_newton_its(&out);
        assert_eq!(its.len(), 6, "{el}: steps were cut: {its:?}");
        assert!(
            its.iter().all(|&k| k <= 8),
            "{el}: Newton iterations {its:?}"
        );
        // Without the predictor Newton runs long enough for its order to show.
        let plain = common::write_case(
            &format!("finite_block_{el}_plain"),
            &common::compressed_block_no_predictor(el, 0.3, 6),
        );
        let (out_plain, stdout) = common::run_case(&plain, 1, &["-snes_monitor"]);
        let its_plain = common::converged_newton_its(&out_plain);
        assert!(its_plain.iter().all(|&k| k <= 8), "{el}: {its_plain:?}");
        let hist = common::snes_monitor_histories(&stdout);
        let ord = orders(&hist);
        eprintln!("{el}: Newton its {its:?} (no predictor {its_plain:?}), orders {ord:?}");
        assert!(!ord.is_empty(), "{el}: no rate could be measured");
        assert!(
            ord.iter().all(|&q| q >= 1.8),
            "{el}: convergence orders {ord:?}"
        );
        // Analytic reaction: homogeneous uniaxial compression.
        let (lambda, mu) = (100.0 * 0.3 / (1.3 * 0.4), 100.0 / 2.6);
        let fz: f64 = 0.7;
        // P_xx(s) = mu (s - 1/s) + lambda ln(s^2 fz) / s = 0, by bisection.
        let pxx = |s: f64| mu * (s - 1.0 / s) + lambda * (s * s * fz).ln() / s;
        let (mut lo, mut hi) = (1.0, 2.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if pxx(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let sl = 0.5 * (lo + hi);
        let pzz = mu * (fz - 1.0 / fz) + lambda * (sl * sl * fz).ln() / fz;
        let history = common::History::read(&out);
        let rows = history.rows();
        let last = rows.last().unwrap();
        let rz = last[history.column("reaction_b.zmax_z")];
        assert!(
            (rz - pzz).abs() < 1e-8 * pzz.abs(),
            "{el}: reaction {rz} vs analytic {pzz}"
        );
    }
}

/// A Neo-Hookean Hex20 cantilever (10 x 1 x 1, E = 1000, nu = 0.3), clamped at x = 0, bent by a
/// follower pressure 0.3 on its top face in 6 steps: the tip deflects by about 40 % of the
/// length. Exercises the nonsymmetric follower-pressure tangent.
#[test]
fn cantilever_under_follower_pressure_converges_quadratically() {
    let case = common::write_case(
        "finite_cantilever",
        &common::cantilever_case("hex20", [10, 1, 2], 6),
    );
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    let its = common::converged_newton_its(&out);
    assert_eq!(its.len(), 6, "steps were cut: {its:?}");
    assert!(its.iter().all(|&k| k <= 8), "Newton iterations {its:?}");
    // The order, measured without the predictor (more iterations above round-off).
    let text = std::fs::read_to_string(&case).unwrap();
    let plain = common::write_case(
        "finite_cantilever_plain",
        &common::with_step_option(&text, "predictor = false"),
    );
    let (_, stdout) = common::run_case(&plain, 1, &["-snes_monitor"]);
    let ord = orders(&common::snes_monitor_histories(&stdout));
    eprintln!("cantilever: Newton its {its:?}, orders {ord:?}");
    assert!(
        ord.len() == 6 && ord.iter().all(|&q| q >= 1.8),
        "orders {ord:?}"
    );
    // The tip really moved through a large rotation.
    let tip: Vec<[f64; 6]> = common::displacements(&out)
        .into_iter()
        .filter(|r| (r[0] - 10.0).abs() < 1e-9)
        .collect();
    let uz = tip.iter().map(|r| r[5]).sum::<f64>() / tip.len() as f64;
    assert!(uz < -3.0, "tip deflection {uz}");
    // `max_displacement` (every scene's summary) is the largest nodal displacement, on 1 and
    // 2 ranks alike.
    let largest = common::displacements(&out)
        .iter()
        .map(|r| (r[3] * r[3] + r[4] * r[4] + r[5] * r[5]).sqrt())
        .fold(0.0, f64::max);
    let (out2, _) = common::run_case(&case, 2, &["-q"]);
    for dir in [&out, &out2] {
        let m = common::metric(dir, "max_displacement");
        assert!(
            (m - largest).abs() <= 1e-10 * largest,
            "{m} against {largest}"
        );
    }
}
