//! Patch tests: a uniform-strain field u = G X is reproduced exactly.
//!
//! Reference: the patch test of Irons (1965) in its displacement form; any conforming
//! isoparametric element contains the linear fields, so u = G X prescribed on the whole boundary
//! must be reproduced at every interior node, and the stress must be sigma(I + G) at every
//! quadrature point, whatever the mesh distortion.
//!
//! Mesh: a 3 x 3 x 3 box of each element type, interior nodes moved randomly by up to 20 % of
//! the element edge. Material: linear elastic (E = 200, nu = 0.3) and compressible Neo-Hookean
//! (a homogeneous finite deformation with |G| ~ 0.1 is an exact equilibrium state too).
//! Passing: `max_displacement_error` and `max_stress_error` below 1e-10 (relative).

mod common;

use common::UNIFORM_STRAIN_GRADIENT as G;

/// A larger gradient, for the finite deformation of the Neo-Hookean patch.
const G_LARGE: &str = "[[0.1, 0.02, -0.03], [0.04, -0.2, 0.01], [0.0, 0.03, 0.15]]";

/// The 3 x 3 x 3 box of `element`, distorted, of `model` (E = 200, nu = 0.3), with u = G X
/// (`gradient` = G) on its whole boundary, in 2 steps.
fn patch_case(element: &str, model: &str, gradient: &str) -> String {
    let mesh = common::box_mesh("b", element, [3, 3, 3], [0.0; 3], [1.0, 1.2, 0.9]);
    let material = common::material(model, 200.0, 0.3);
    let check = common::uniform_strain_check(
        gradient,
        &["b.xmin", "b.xmax", "b.ymin", "b.ymax", "b.zmin", "b.zmax"],
    );
    format!("\n{mesh}distort = 0.2\n{material}[steps]\ncount = 2\n{check}")
}

fn check_patch(element: &str, model: &str, gradient: &str) {
    let case = common::write_case(
        &format!("patch_{element}_{model}"),
        &patch_case(element, model, gradient),
    );
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    let du = common::metric(&out, "max_displacement_error");
    let ds = common::metric(&out, "max_stress_error");
    assert!(du < 1e-10, "{element} {model}: displacement error {du:e}");
    assert!(ds < 1e-10, "{element} {model}: stress error {ds:e}");
}

#[test]
fn linear_elastic_patch_every_element_distorted() {
    for el in ["hex8", "hex20", "hex27", "tet4", "tet10"] {
        check_patch(el, "linear_elastic", G);
    }
}

/// A selected quadrature degree (here a richer rule than the default) keeps the patch exact.
#[test]
fn patch_holds_with_a_selected_quadrature_degree() {
    let toml = format!(
        "quadrature_degree = 7\n{}",
        patch_case("hex27", "linear_elastic", G)
    );
    let case = common::write_case("patch_hex27_q7", &toml);
    let (out, _) = common::run_case(&case, 1, &["-q"]);
    assert!(common::metric(&out, "max_displacement_error") < 1e-10);
    assert!(common::metric(&out, "max_stress_error") < 1e-10);
}

#[test]
fn neo_hookean_patch_every_element_distorted() {
    for el in ["hex8", "hex20", "hex27", "tet4", "tet10"] {
        check_patch(el, "neo_hookean", G_LARGE);
    }
}
