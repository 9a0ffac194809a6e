//! Case texts: the TOML of the small scenes that several test files build, each built once
//! here (with parameters for what the files vary), the pieces they share (a box mesh, a
//! material, symmetry planes, a uniform-strain boundary), the edits several files make to a
//! case, and the shipped scenes of `cases/`.
//!
//! The texts are built piece by piece in the order a case file lists its tables, each piece
//! ending in a newline, so that a test's edits (`text.replace(...)`) find the lines they
//! expect.

use std::fmt::Debug;
use std::path::{Path, PathBuf};

/// The folder of the shipped scenes, `cases/`.
pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// The folder of the shipped scene `cases/<scene>`.
pub fn scene_dir(scene: &str) -> PathBuf {
    cases_dir().join(scene)
}

/// The case text of the shipped scene `cases/<scene>`.
pub fn scene_text(scene: &str) -> String {
    std::fs::read_to_string(scene_dir(scene).join("case.toml")).unwrap()
}

/// `[a, b, c]` as TOML writes it (`[3, 3, 1]`, `[0.0, 0.25, 1.0]`).
fn triple<T: Debug>(v: [T; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

/// A `[[mesh]]` of the box generator: body `body` of `element`, `divisions` elements along x,
/// y and z, from the corner `lo` to the corner `hi`.
pub fn box_mesh(
    body: &str,
    element: &str,
    divisions: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
) -> String {
    format!(
        "[[mesh]]\nbody = \"{body}\"\ngenerator = \"box\"\nelement = \"{element}\"\n\
         divisions = {}\nlo = {}\nhi = {}\n",
        triple(divisions),
        triple(lo),
        triple(hi)
    )
}

/// A `[[material]]` of every body: `model` with Young's modulus `young` and Poisson's ratio
/// `poisson`.
pub fn material(model: &str, young: f64, poisson: f64) -> String {
    format!("[[material]]\n{}", material_keys(model, young, poisson))
}

/// A `[[material]]` of the body `body` ([`material`]).
pub fn body_material(body: &str, model: &str, young: f64, poisson: f64) -> String {
    format!(
        "[[material]]\nbody = \"{body}\"\n{}",
        material_keys(model, young, poisson)
    )
}

/// The keys of a `[[material]]` after its body.
fn material_keys(model: &str, young: f64, poisson: f64) -> String {
    format!("model = \"{model}\"\nyoung = {young:?}\npoisson = {poisson:?}\n")
}

/// A `[[symmetry]]` plane for each `(set, normal)`.
pub fn symmetry(planes: &[(&str, &str)]) -> String {
    planes
        .iter()
        .map(|(set, normal)| format!("[[symmetry]]\nset = \"{set}\"\nnormal = \"{normal}\"\n"))
        .collect()
}

/// Two blocks stacked along z on the unit square: `low` from z = 0 to 0.5 and `up` from 0.5 to
/// 1, of `element` with `low_divisions` and `up_divisions` elements, both of `model` with
/// Young's modulus `young` (nu = 0.3). Their meshes and materials: the interface between
/// `low.zmax` and `up.zmin` and the loads are the caller's.
pub fn stacked_blocks(
    element: &str,
    low_divisions: [usize; 3],
    up_divisions: [usize; 3],
    model: &str,
    young: f64,
) -> String {
    [
        box_mesh("low", element, low_divisions, [0.0; 3], [1.0, 1.0, 0.5]),
        box_mesh("up", element, up_divisions, [0.0, 0.0, 0.5], [1.0; 3]),
        body_material("low", model, young, 0.3),
        body_material("up", model, young, 0.3),
    ]
    .concat()
}

/// The displacement gradient G of the patch tests' uniform strain u = G X.
pub const UNIFORM_STRAIN_GRADIENT: &str =
    "[[0.01, 0.002, -0.003], [0.004, -0.02, 0.001], [0.0, 0.003, 0.015]]";

/// A patch test's check of the uniform strain u = G X (`gradient` = G): the exact solution
/// (`[verification]` of kind `uniform_strain`), and u = G X prescribed on every set of `sets`.
pub fn uniform_strain_check(gradient: &str, sets: &[&str]) -> String {
    let mut s = format!("[verification]\nkind = \"uniform_strain\"\ngradient = {gradient}\n");
    for set in sets {
        s.push_str(&format!(
            "[[dirichlet]]\nset = \"{set}\"\ncomponents = [\"x\", \"y\", \"z\"]\ngradient = {gradient}\n"
        ));
    }
    s
}

/// A Lamé thick-sphere octant scene (E = 1000, nu = 0.3, a = 1, b = 2, p = 1, dead load).
pub fn thick_sphere_case(element: &str, n: usize) -> String {
    format!(
        r#"
name = "thick_sphere"
[[mesh]]
body = "sphere"
generator = "thick_sphere_octant"
element = "{element}"
n_circ = {n}
n_rad = {n}
inner_radius = 1.0
outer_radius = 2.0
{}{}[[pressure]]
set = "sphere.inner"
value = 1.0
follower = false
[verification]
kind = "lame_sphere"
inner_radius = 1.0
outer_radius = 2.0
pressure = 1.0
"#,
        material("linear_elastic", 1000.0, 0.3),
        symmetry(&[
            ("sphere.symx", "x"),
            ("sphere.symy", "y"),
            ("sphere.symz", "z")
        ]),
    )
}

/// [`compressed_block`] with the load-step predictor off, so that the whole prescribed
/// increment reaches the first Newton iterate (what the step-cutting tests need) and Newton
/// takes enough iterations for its asymptotic order to show.
pub fn compressed_block_no_predictor(element: &str, strain: f64, steps: usize) -> String {
    with_step_option(
        &compressed_block(element, strain, steps),
        "predictor = false",
    )
}

/// [`compressed_block_no_predictor`] of Hex8 by 60 % in one step that may not be cut
/// (`max_cuts = 0`): the first Newton iterate inverts its top elements, and the run fails.
pub fn uncuttable_crushed_block() -> String {
    compressed_block_no_predictor("hex8", 0.6, 1).replace("count = 1", "count = 1\nmax_cuts = 0")
}

/// A Neo-Hookean block, compressed by `strain` along z in `steps` steps, free to expand sideways
/// (symmetry planes on xmin, ymin, zmin).
pub fn compressed_block(element: &str, strain: f64, steps: usize) -> String {
    format!(
        r#"
{}{}{}[[dirichlet]]
set = "b.zmax"
components = ["z"]
value = [-{strain}]
[steps]
count = {steps}
"#,
        box_mesh("b", element, [3, 3, 3], [0.0; 3], [1.0; 3]),
        material("neo_hookean", 100.0, 0.3),
        symmetry(&[("b.xmin", "x"), ("b.ymin", "y"), ("b.zmin", "z")]),
    )
}

/// A 1 x 1 x 4 linear-elastic column of Hex20 (E = 1000, nu = 0.25), clamped at z = 0, with
/// the tables `extra` after it.
pub fn column_case(extra: &str) -> String {
    format!(
        r#"
{}{}[[dirichlet]]
set = "c.zmin"
components = ["x", "y", "z"]
{extra}
"#,
        box_mesh("c", "hex20", [1, 1, 4], [0.0; 3], [1.0, 1.0, 4.0]),
        material("linear_elastic", 1000.0, 0.25),
    )
}

/// The Coulomb coefficient of [`slide_case`] (its text reads `friction = 0.3`).
pub const SLIDE_FRICTION: f64 = 0.3;

/// A small frictional slide (Hex8, one pass, mu = 0.3): compressed, then the upper block pushed
/// sideways, with the upper block narrower than the lower one so that its edges slide over the
/// lower surface.
pub fn slide_case(steps: usize) -> String {
    let bodies = [
        box_mesh("low", "hex8", [3, 2, 1], [0.0; 3], [1.5, 1.0, 0.5]),
        box_mesh("up", "hex8", [2, 2, 1], [0.25, 0.1, 0.5], [0.95, 0.9, 1.0]),
        body_material("low", "neo_hookean", 1000.0, 0.3),
        body_material("up", "neo_hookean", 1000.0, 0.3),
        symmetry(&[
            ("low.zmin", "z"),
            ("low.xmin", "x"),
            ("low.ymin", "y"),
            ("up.ymin", "y"),
        ]),
    ]
    .concat();
    format!(
        r#"
{bodies}[[dirichlet]]
set = "up.zmax"
components = ["z"]
value = [-0.02]
curve = {{ kind = "table", table = [[0.0, 0.0], [0.3, 1.0], [1.0, 1.0]] }}
[[dirichlet]]
set = "up.zmax"
components = ["x"]
value = [0.2]
curve = {{ kind = "table", table = [[0.0, 0.0], [0.3, 0.0], [1.0, 1.0]] }}
[[interface]]
name = "slide"
kind = "contact"
secondary = "up.zmin"
primary = "low.zmax"
friction = {SLIDE_FRICTION}
[steps]
count = {steps}
"#
    )
}

/// The slide of [`slide_case`] with the lower, larger surface secondary: the nodes of its
/// surface under the upper block's edges are partly covered.
pub fn swapped_slide_case(steps: usize) -> String {
    let slide = slide_case(steps);
    let swapped = slide.replace(
        "secondary = \"up.zmin\"\nprimary = \"low.zmax\"",
        "secondary = \"low.zmax\"\nprimary = \"up.zmin\"",
    );
    assert_ne!(slide, swapped);
    swapped
}

/// The cantilever of `cases/cantilever`: a 10 x 1 x 1 beam of `element`, clamped at x = 0, a
/// follower pressure 0.3 on its top face, compressible Neo-Hookean (E = 1000, nu = 0.3).
pub fn cantilever_case(element: &str, divisions: [usize; 3], steps: usize) -> String {
    format!(
        r#"
[[mesh]]
body = "beam"
generator = "beam"
element = "{element}"
divisions = {}
length = 10.0
width = 1.0
height = 1.0
{}[[dirichlet]]
set = "beam.xmin"
components = ["x", "y", "z"]
[[pressure]]
set = "beam.zmax"
value = 0.3
[steps]
count = {steps}
"#,
        triple(divisions),
        material("neo_hookean", 1000.0, 0.3),
    )
}

/// A case text with `line` (`predictor = false`) first in its `[steps]` table.
pub fn with_step_option(text: &str, line: &str) -> String {
    let out = text.replacen("[steps]\n", &format!("[steps]\n{line}\n"), 1);
    assert_ne!(out, text, "no [steps] table");
    out
}

/// A case text whose first contact interface is node-on-segment
/// (`method = "node_on_segment"`), for a case text that does not choose.
pub fn with_node_on_segment(text: &str) -> String {
    let out = text.replacen(
        "kind = \"contact\"\n",
        "kind = \"contact\"\nmethod = \"node_on_segment\"\n",
        1,
    );
    assert_ne!(out, text, "no contact interface");
    out
}

/// A case text whose first interface splits its overlaps into fans of pallets
/// (`pallets = "fan"`).
pub fn with_fan_pallets(text: &str) -> String {
    with_pallets(text, "fan")
}

/// A case text whose first interface splits its overlaps into pallets as `split` says
/// (`pallets = "<split>"`), for a case text that does not choose.
pub fn with_pallets(text: &str, split: &str) -> String {
    assert!(
        !text.contains("\npallets ="),
        "the case already chooses its pallets"
    );
    let out = text.replacen(
        "[[interface]]\n",
        &format!("[[interface]]\npallets = \"{split}\"\n"),
        1,
    );
    assert_ne!(out, text, "no interface to split into pallets");
    out
}
