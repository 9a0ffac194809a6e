//! Loads and reactions against statics: the support of a column carries its weight and the
//! pressure on its top, and the symmetry planes of the Lamé sphere carry the hoop stress across
//! them.

mod common;

/// The value of the history column `name` (a reaction) after the last step.
fn reaction(out: &std::path::Path, name: &str) -> f64 {
    let history = common::History::read(out);
    let k = history.column(name);
    let last = history.lines.last().unwrap();
    last.split(',').nth(k).unwrap().parse().unwrap()
}

/// Statics: the support carries the weight (body force -2 per unit volume on volume 4 gives a
/// reaction of +8 along z) and a dead pressure of 3 on the top (area 1) adds +3.
#[test]
fn reactions_balance_body_force_and_pressure() {
    let case = common::write_case(
        "statics_column",
        &common::column_case(
            "[[body_force]]\nvalue = [0.0, 0.0, -2.0]\n[[pressure]]\nset = \"c.zmax\"\nvalue = 3.0\nfollower = false\n",
        ),
    );
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    let rz = reaction(&out, "reaction_c.zmin_z");
    assert!((rz - 11.0).abs() < 1e-10, "reaction {rz}");
    let rx = reaction(&out, "reaction_c.zmin_x");
    assert!(rx.abs() < 1e-10, "reaction x {rx}");
}

/// Lamé sphere: the reaction on the symmetry plane x = 0 balances the hoop stress across it,
/// R_x = -int_a^b sigma_tt (pi / 2) r dr = -pi / 4 for a = 1, b = 2, p = 1 (tension: the plane
/// pulls). Hex20, n = 2: within 1e-4 relative (discretization error).
#[test]
fn sphere_symmetry_reaction_is_minus_pi_over_four() {
    let case = common::write_case("sphere_reaction", &common::thick_sphere_case("hex20", 2));
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    let exact = -std::f64::consts::FRAC_PI_4;
    for (set, c) in [("symx", "x"), ("symy", "y"), ("symz", "z")] {
        let r = reaction(&out, &format!("reaction_sphere.{set}_{c}"));
        assert!(
            (r - exact).abs() < 1e-4 * exact.abs(),
            "{set}: {r} vs {exact}"
        );
    }
}
