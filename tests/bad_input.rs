//! Bad input ends in one clear line on stderr: never a panic, an abort, a hang or NaN output.
//!
//! Every row of [`rows`] is a small scene that is wrong in one way: a case file, an extra file
//! (a `.msh`, a PETSc options file) and the command line. Each row is written into its own fresh
//! folder under `CARGO_TARGET_TMPDIR` and the `mortar` binary is run there directly (one MPI
//! rank, no mpirun), with `RUST_BACKTRACE` unset. For every row the test checks that:
//!
//! - the process ends within [`TIMEOUT`] (else it is killed and the row fails);
//! - it exits with a non-zero code (an exit by signal, e.g. an abort, fails the row);
//! - stderr holds exactly one non-empty line, which starts with `mortar: error:` and contains
//!   one of the row's culprits (the key, set, element, file or option at fault);
//! - stderr contains neither `panicked` nor `RUST_BACKTRACE`;
//! - no file in the output folder (`run` only) contains a NaN.
//!
//! All rows run, then one assertion lists every failing row with its stderr. Each row's folder
//! keeps its inputs, `stdout.txt` and `stderr.txt` after the run.
//!
//! A control test runs the unedited [`VALID`] scene and expects success, so the rows are known
//! to fail for the reason they were written for.

mod common;

use std::fmt::Write as _;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::thread::sleep;
use std::time::{Duration, Instant};

/// Longest a row may run before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(60);

/// A tiny valid scene: one hex8 pulled along x. Rows edit it.
const VALID: &str = r#"[[mesh]]
body = "b"
generator = "box"
element = "hex8"
divisions = [1, 1, 1]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]

[[material]]
body = "b"
model = "linear_elastic"
young = 1000.0
poisson = 0.3

[[dirichlet]]
set = "b.xmin"
components = ["x", "y", "z"]

[[dirichlet]]
set = "b.xmax"
components = ["x"]
value = [0.01]
"#;

/// The material block of [`VALID`] (`edit` checks that it occurs there).
const MATERIAL: &str = r#"[[material]]
body = "b"
model = "linear_elastic"
young = 1000.0
poisson = 0.3
"#;

/// A scene read from `mesh.msh`.
const GMSH: &str = r#"[[mesh]]
generator = "gmsh"
file = "mesh.msh"

[[material]]
model = "linear_elastic"
young = 1000.0
poisson = 0.3
"#;

/// A thick sphere octant with its radii swapped.
const SPHERE_SWAPPED_RADII: &str = r#"[[mesh]]
body = "s"
generator = "thick_sphere_octant"
element = "hex8"
n_circ = 1
n_rad = 1
inner_radius = 2.0
outer_radius = 1.0

[[material]]
model = "linear_elastic"
young = 1000.0
poisson = 0.3
"#;

/// A quarter hemisphere without its radius.
const HEMISPHERE_NO_RADIUS: &str = r#"[[mesh]]
body = "ball"
generator = "hemisphere_quarter"
element = "hex8"
n_circ = 2
n_rad = 1

[[material]]
model = "linear_elastic"
young = 1000.0
poisson = 0.3
"#;

/// The subcommand a row runs.
#[derive(Clone, Copy, Debug)]
enum Sub {
    Run,
    Check,
}

/// The content of an extra file written next to the case file.
enum Content {
    /// This text.
    Text(&'static str),
    /// A copy of this file under `tests/data/`.
    Data(&'static str),
}

/// One bad input and what its error must name.
struct Row {
    /// Unique, also the name of the row's folder.
    name: &'static str,
    /// The case file's text, written as `case.toml`; `None` runs on a missing `no_such_case.toml`.
    case: Option<String>,
    /// Extra files: (name in the row's folder, content).
    files: Vec<(&'static str, Content)>,
    sub: Sub,
    /// Arguments after the case file. `run` rows get `--out out` unless they pass `--out`.
    args: Vec<&'static str>,
    /// The error line must contain at least one of these.
    culprit: Vec<&'static str>,
}

impl Row {
    fn new(name: &'static str, sub: Sub, case: Option<String>, culprit: &'static str) -> Row {
        Row {
            name,
            case,
            files: Vec::new(),
            sub,
            args: Vec::new(),
            culprit: vec![culprit],
        }
    }

    fn file(mut self, name: &'static str, content: Content) -> Row {
        self.files.push((name, content));
        self
    }

    fn args(mut self, args: &[&'static str]) -> Row {
        self.args.extend_from_slice(args);
        self
    }

    /// Also accepts `other` as the culprit.
    fn or(mut self, other: &'static str) -> Row {
        self.culprit.push(other);
        self
    }
}

fn check(name: &'static str, case: Option<String>, culprit: &'static str) -> Row {
    Row::new(name, Sub::Check, case, culprit)
}

fn run(name: &'static str, case: Option<String>, culprit: &'static str) -> Row {
    Row::new(name, Sub::Run, case, culprit)
}

/// `base` with its single occurrence of `old` replaced by `new`.
fn edit(base: &str, old: &str, new: &str) -> String {
    assert_eq!(
        base.matches(old).count(),
        1,
        "'{old}' must occur once in:\n{base}"
    );
    base.replacen(old, new, 1)
}

/// [`VALID`] with one edit.
fn valid_with(old: &str, new: &str) -> Option<String> {
    text(&edit(VALID, old, new))
}

/// [`VALID`] with top-level keys in front (they must precede the tables).
fn valid_top(keys: &str) -> Option<String> {
    text(&format!("{keys}\n{VALID}"))
}

/// [`VALID`] with more tables after it (or more keys of its last table, `dirichlet[1]`).
fn valid_plus(tables: &str) -> Option<String> {
    text(&format!("{VALID}\n{tables}"))
}

/// A case file's text, as a row wants it.
fn text(s: &str) -> Option<String> {
    Some(s.to_string())
}

/// The table of bad inputs.
fn rows() -> Vec<Row> {
    [
        case_file_and_mesh_rows(),
        material_rows(),
        load_rows(),
        interface_rows(),
        step_newton_and_verification_rows(),
        name_and_bound_rows(),
        overflow_rows(),
        option_and_command_line_rows(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// Rows of the table: The case file as a whole, its `[[mesh]]` tables and Gmsh files.
fn case_file_and_mesh_rows() -> Vec<Row> {
    use Content::{Data, Text};
    vec![
        // --- The case file as a whole.
        check("missing_case_file", None, "no_such_case.toml"),
        check("not_toml", text("this is [not toml\n"), "case.toml").or("TOML"),
        check("empty_case_file", text(""), "mesh"),
        check(
            "unknown_top_level_key",
            valid_top(r#"colour = "red""#),
            "colour",
        ),
        check("no_mesh_parts", text("mesh = []\n"), "[[mesh]]"),
        // --- [[mesh]].
        check(
            "unknown_mesh_key",
            valid_with("divisions", "nodes_per_edge = 3\ndivisions"),
            "nodes_per_edge",
        ),
        check(
            "unknown_generator",
            valid_with(r#""box""#, r#""cylinder""#),
            "cylinder",
        ),
        check(
            "unknown_element",
            valid_with(r#""hex8""#, r#""hex9""#),
            "hex9",
        ),
        check(
            "divisions_with_zero",
            valid_with("[1, 1, 1]", "[1, 0, 1]"),
            "mesh[0].divisions",
        ),
        check(
            "divisions_negative",
            valid_with("[1, 1, 1]", "[1, -1, 1]"),
            "divisions",
        ),
        check(
            "box_hi_not_above_lo",
            valid_with("hi = [1.0, 1.0, 1.0]", "hi = [1.0, 0.0, 1.0]"),
            "mesh[0]: hi",
        ),
        check(
            "box_lo_nan",
            valid_with("lo = [0.0, 0.0, 0.0]", "lo = [nan, 0.0, 0.0]"),
            "mesh[0].lo",
        ),
        check(
            "distort_too_large",
            valid_with("divisions", "distort = 0.5\ndivisions"),
            "distort",
        ),
        check(
            "sphere_outer_not_above_inner",
            text(SPHERE_SWAPPED_RADII),
            "outer_radius",
        ),
        check(
            "hemisphere_without_radius",
            text(HEMISPHERE_NO_RADIUS),
            "mesh[0].radius",
        ),
        check(
            "hemisphere_of_tetrahedra",
            text(&edit(
                &HEMISPHERE_NO_RADIUS.replace("n_rad = 1", "n_rad = 1\nradius = 1.0"),
                r#""hex8""#,
                r#""tet4""#,
            )),
            "mesh[0].element",
        ),
        check(
            "hemisphere_pole_grading_below_one",
            text(&HEMISPHERE_NO_RADIUS.replace("n_rad = 1", "n_rad = 1\nradius = 1.0\npole_grading = 0.5")),
            "mesh[0].pole_grading",
        ),
        check(
            "box_grading_zero",
            valid_with("divisions = [1, 1, 1]", "divisions = [1, 1, 1]\ngrading = [1.0, 0.0, 1.0]"),
            "mesh[0].grading",
        ),
        check(
            "box_grading_subnormal",
            valid_with("divisions = [1, 1, 1]", "divisions = [1, 1, 1]\ngrading = [1.0, 1e-310, 1.0]\ngrading_zone = [0.0, 0.5, 0.0]"),
            "mesh[0].grading",
        ),
        check(
            "box_grading_zone_on_an_ungraded_axis",
            valid_with("divisions = [1, 1, 1]", "divisions = [1, 1, 1]\ngrading_zone = [0.5, 0.0, 0.0]"),
            "mesh[0].grading_zone",
        ),
        check(
            "hemisphere_pole_zone_without_pole_grading",
            text(&HEMISPHERE_NO_RADIUS.replace("n_rad = 1", "n_rad = 1\nradius = 1.0\npole_zone = 0.2")),
            "mesh[0].pole_zone",
        ),
        // --- Gmsh files.
        run("missing_gmsh_file", text(GMSH), "mesh.msh"),
        check("truncated_msh", text(GMSH), "mesh.msh")
            .file("mesh.msh", Data("truncated.msh"))
            .or("truncated"),
        check("msh_version_22", text(GMSH), "version 2.2").file("mesh.msh", Data("version22.msh")),
        check("msh_not_gmsh", text(GMSH), "not a Gmsh file")
            .file("mesh.msh", Text("solid cube\nendsolid cube\n")),
        check("msh_unsupported_element", text(GMSH), "element type 6")
            .file("mesh.msh", Data("unsupported.msh")),
        check("msh_surface_not_a_face", text(GMSH), "surface element 4")
            .file("mesh.msh", Data("not_a_face.msh")),
        check("msh_inverted_hex", text(GMSH), "Gmsh element 7")
            .file("mesh.msh", Data("bad/inverted_hex.msh")),
        check("msh_zero_node_count", text(GMSH), "mesh.msh")
            .file("mesh.msh", Data("bad/zero_node_count.msh")),
        check("msh_huge_node_count", text(GMSH), "mesh.msh")
            .file("mesh.msh", Data("bad/huge_node_count.msh")),
    ]
}

/// Rows of the table: `[[material]]`.
fn material_rows() -> Vec<Row> {
    vec![
        // --- [[material]].
        check(
            "young_wrong_type",
            valid_with("young = 1000.0", r#"young = "abc""#),
            "young",
        ),
        check(
            "young_zero",
            valid_with("young = 1000.0", "young = 0.0"),
            "young = 0",
        ),
        check(
            "young_negative",
            valid_with("young = 1000.0", "young = -5.0"),
            "young = -5",
        ),
        run(
            "poisson_half",
            valid_with("poisson = 0.3", "poisson = 0.5"),
            "poisson = 0.5",
        ),
        check(
            "poisson_minus_one",
            valid_with("poisson = 0.3", "poisson = -1.0"),
            "poisson = -1",
        ),
        check(
            "poisson_nan",
            valid_with("poisson = 0.3", "poisson = nan"),
            "poisson = NaN",
        ),
        check(
            "unknown_material_model",
            valid_with(r#""linear_elastic""#, r#""mooney_rivlin""#),
            "mooney_rivlin",
        ),
        check(
            "unknown_material_key",
            valid_with("young = 1000.0", "youngs = 1000.0"),
            "youngs",
        ),
        check(
            "material_for_missing_body",
            valid_with(MATERIAL, &MATERIAL.replace(r#""b""#, r#""ghost""#)),
            "ghost",
        ),
        check("missing_material", valid_with(MATERIAL, ""), "body 'b'"),
        check(
            "two_materials_for_one_body",
            valid_plus(MATERIAL),
            "material[1]",
        ),
    ]
}

/// Rows of the table: Constraints and loads.
fn load_rows() -> Vec<Row> {
    vec![
        // --- Constraints and loads.
        check(
            "symmetry_missing_set",
            valid_plus(
                r#"[[symmetry]]
set = "b.nowhere"
normal = "x"
"#,
            ),
            "b.nowhere",
        ),
        check(
            "symmetry_bad_normal",
            valid_plus(
                r#"[[symmetry]]
set = "b.ymin"
normal = "w"
"#,
            ),
            "symmetry[0].normal",
        ),
        check(
            "pressure_missing_face_set",
            valid_plus(
                r#"[[pressure]]
set = "b.lid"
value = 1.0
"#,
            ),
            "b.lid",
        ),
        check(
            "dirichlet_component_w",
            valid_with(r#"["x", "y", "z"]"#, r#"["x", "y", "w"]"#),
            r#""w""#,
        ),
        check(
            "dirichlet_value_count",
            valid_with("value = [0.01]", "value = [0.01, 0.02]"),
            "dirichlet[1].value",
        ),
        check(
            "dirichlet_value_infinite",
            valid_with("value = [0.01]", "value = [inf]"),
            "dirichlet[1].value",
        ),
        check(
            "dirichlet_value_and_gradient",
            valid_plus("gradient = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n"),
            "dirichlet[1]",
        ),
        check(
            "table_curve_decreasing_t",
            valid_plus(
                r#"[dirichlet.curve]
kind = "table"
table = [[0.0, 0.0], [0.5, 1.0], [0.25, 1.0]]
"#,
            ),
            "dirichlet[1].curve.table",
        ),
        check(
            "unknown_curve_kind",
            valid_plus("[dirichlet.curve]\nkind = \"sine\"\n"),
            "sine",
        ),
        check(
            "body_force_missing_body",
            valid_plus(
                r#"[[body_force]]
body = "ghost"
value = [0.0, 0.0, -1.0]
"#,
            ),
            "body_force[0].body",
        ),
        check(
            "reactions_on_unconstrained_set",
            valid_plus("[output]\nreactions = [\"b.ymax\"]\n"),
            "b.ymax",
        ),
    ]
}

/// Rows of the table: `[[interface]]`.
fn interface_rows() -> Vec<Row> {
    vec![
        // --- Interfaces.
        check(
            "interface_unknown_kind",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"glued\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\n"),
            "interface[0].kind",
        ),
        check(
            "interface_missing_face_set",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.top\"\nprimary = \"b.zmin\"\n"),
            "interface[0].secondary",
        ),
        check(
            "interface_three_passes",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npasses = 3\n"),
            "interface[0].passes",
        ),
        check(
            "interface_scheme_four",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nscheme = 4\n"),
            "interface[0].scheme",
        ),
        check(
            "contact_negative_friction",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nfriction = -0.1\n"),
            "interface[0].friction",
        ),
        check(
            "contact_zero_penalty",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty = 0.0\n"),
            "interface[0].penalty",
        ),
        check(
            "contact_nan_tangential_penalty",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\ntangential_penalty = nan\n"),
            "interface[0].tangential_penalty",
        ),
        check(
            "contact_negative_uzawa_slip_tol",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_slip_tol = -1e-4\n"),
            "interface[0].uzawa_slip_tol",
        ),
        check(
            "uzawa_slip_tol_on_tied_interface",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_slip_tol = 1e-4\n"),
            "interface[0].uzawa_slip_tol",
        ),
        check(
            "contact_zero_uzawa_slip_motion",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_slip_motion = 0.0\n"),
            "interface[0].uzawa_slip_motion",
        ),
        check(
            "uzawa_slip_motion_on_tied_interface",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_slip_motion = 0.1\n"),
            "interface[0].uzawa_slip_motion: only for kind = \"contact\"",
        ),
        check(
            "contact_unknown_uzawa_relaxation",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_relaxation = \"anderson\"\n"),
            "interface[0].uzawa_relaxation = \"anderson\": must be \"aitken\" or \"none\"",
        ),
        check(
            "uzawa_relaxation_on_tied_interface",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_relaxation = \"none\"\n"),
            "interface[0].uzawa_relaxation: only for kind = \"contact\"",
        ),
        check(
            "contact_unknown_method",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nmethod = \"nts\"\n"),
            "interface[0].method",
        ),
        check(
            "interface_unknown_pallet_split",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npallets = \"delaunay\"\n"),
            "interface[0].pallets",
        ),
        check(
            "method_on_tied_interface",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nmethod = \"node_on_segment\"\n"),
            "interface[0].method",
        ),
        check(
            "contact_penalty_shrinking",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty_growth = 0.5\n"),
            "interface[0].penalty_growth",
        ),
        check(
            "friction_on_tied_interface",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"tied\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nfriction = 0.3\n"),
            "interface[0].friction",
        ),
        check(
            "contact_patch_without_pressure",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\n\n[verification]\nkind = \"contact_patch\"\nstress = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]\n"),
            "pressure",
        ),
    ]
}

/// Rows of the table: Steps, Newton, verification.
fn step_newton_and_verification_rows() -> Vec<Row> {
    vec![
        // --- Steps, Newton, verification.
        check(
            "rotation_with_zero_axis",
            valid_plus("[[dirichlet]]\nset = \"b.zmin\"\ncomponents = [\"x\"]\nrotation = { axis = [0.0, 0.0, 0.0], angle = 1.0 }\n"),
            "dirichlet[2].rotation.axis",
        ),
        check(
            "track_unknown_set",
            valid_plus("[output]\ntrack = [\"b.nowhere\"]\n"),
            "output.track[0]",
        ),
        check(
            "key_not_for_this_generator",
            valid_with("divisions = [1, 1, 1]", "divisions = [1, 1, 1]\nn_circ = 3"),
            "mesh[0].n_circ",
        ),
        check(
            "quadrature_degree_zero",
            valid_top("quadrature_degree = 0\n"),
            "quadrature_degree",
        ),
        check(
            "steps_count_zero",
            valid_plus("[steps]\ncount = 0\n"),
            "steps.count",
        ),
        check(
            "expect_without_comparison",
            text(&format!("expect = [\"max_newton_its 8\"]\n{VALID}")),
            "expect[0]",
        ),
        check(
            "output_figure_missing",
            valid_plus("[output]\nfigure = \"no_such_study.toml\"\n"),
            "output.figure",
        ),
        check(
            "steps_unknown_on_failure",
            valid_plus("[steps]\ncount = 1\non_failure = \"ignore\"\n"),
            "steps.on_failure",
        ),
        check(
            "steps_unknown_predictor_tangent",
            valid_plus("[steps]\ncount = 1\npredictor_tangent = \"stale\"\n"),
            "steps.predictor_tangent",
        ),
        check(
            "newton_rtol_zero",
            valid_plus("[newton]\nrtol = 0.0\n"),
            "rtol",
        ),
        check(
            "newton_augmented_rtol_one",
            valid_plus("[newton]\naugmented_rtol = 1.0\n"),
            "newton.augmented_rtol",
        ),
        check(
            "newton_linear_solver_unknown",
            valid_plus("[newton]\nlinear_solver = \"fast\"\n"),
            "newton.linear_solver",
        ),
        check(
            "newton_direct_below_negative",
            valid_plus("[newton]\ndirect_below = -5\n"),
            "newton.direct_below",
        ),
        run(
            "newton_max_it_absurd",
            valid_plus("[newton]\nmax_it = 100000000000000\n"),
            "max_it",
        ),
        check(
            "verification_kind_unknown",
            valid_plus("[verification]\nkind = \"boussinesq\"\n"),
            "boussinesq",
        ),
        check(
            "hertz_without_interface",
            valid_plus("[verification]\nkind = \"hertz\"\nradius = 1.0\nmodel_fraction = 0.25\n"),
            "verification.interface",
        ),
        check(
            "hertz_without_radius",
            valid_plus("[verification]\nkind = \"hertz\"\ninterface = \"i\"\nmodel_fraction = 0.25\n"),
            "verification.radius",
        ),
        check(
            "hertz_on_a_missing_interface",
            valid_plus("[verification]\nkind = \"hertz\"\nradius = 1.0\ninterface = \"nowhere\"\nmodel_fraction = 0.25\n"),
            "nowhere",
        ),
        check(
            "hertz_with_a_lame_key",
            valid_plus("[verification]\nkind = \"hertz\"\nradius = 1.0\ninterface = \"i\"\nmodel_fraction = 0.25\ninner_radius = 1.0\n"),
            "verification.inner_radius",
        ),
    ]
}

/// Rows of the table: Names that become file names, duplicates, bounds.
fn name_and_bound_rows() -> Vec<Row> {
    use Content::Text;
    vec![
        // --- Names that become file names, duplicates, bounds (found by a fuzzing sweep).
        check(
            "name_with_a_path",
            valid_top(r#"name = "../../escaped""#),
            "name",
        ),
        check("name_empty", valid_top(r#"name = """#), "name"),
        check(
            "interface_name_with_a_path",
            valid_plus("[[interface]]\nname = \"a/b\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\n"),
            "interface[0].name",
        ),
        check(
            "interface_names_twice",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\n\n[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.ymax\"\nprimary = \"b.ymin\"\n"),
            "interface[1].name",
        ),
        check(
            "contact_penalty_overflowing",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty = 1e300\n"),
            "interface[0].penalty",
        ),
        check(
            "uzawa_max_absurd",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nuzawa_max = 100000000\n"),
            "interface[0].uzawa_max",
        ),
        check(
            "max_cuts_below_round_off",
            valid_plus("[steps]\ncount = 1\nmax_cuts = 1100\n"),
            "steps.max_cuts",
        ),
        check(
            "dirichlet_component_twice",
            valid_with(
                "components = [\"x\"]\nvalue = [0.01]",
                "components = [\"x\", \"x\"]\nvalue = [0.01, 0.02]",
            ),
            "dirichlet[1].components",
        ),
        run(
            "dirichlet_gradient_nan",
            valid_plus("[[dirichlet]]\nset = \"b.zmax\"\ncomponents = [\"z\"]\ngradient = [[nan, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n"),
            "dirichlet[2].gradient",
        ),
        check(
            "young_subnormal",
            valid_with("young = 1000.0", "young = 1e-320"),
            "young",
        ),
        check(
            "track_twice",
            valid_plus("[output]\ntrack = [\"b.xmax\", \"b.xmax\"]\n"),
            "output.track[1]",
        ),
        check(
            "uniform_strain_gradient_nan",
            valid_plus("[verification]\nkind = \"uniform_strain\"\ngradient = [[nan, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n"),
            "verification.gradient",
        ),
        check(
            "contact_patch_without_contact",
            valid_plus("[verification]\nkind = \"contact_patch\"\nstress = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]\npressure = 1.0\n"),
            "contact interface",
        ),
        check(
            "gmsh_part_with_a_body",
            text("[[mesh]]\nbody = \"x\"\ngenerator = \"gmsh\"\nfile = \"m.msh\"\n"),
            "mesh[0].body",
        ),
        run("second_file_after_the_case", text(VALID), "extra.toml").args(&["extra.toml"]),
        run("log_view_unwritable", text(VALID), "-log_view")
            .file("not_a_folder", Text("a file\n"))
            .args(&["-log_view", ":not_a_folder/log.txt"]),
        run("stray_word_after_an_option_value", text(VALID), "extra.toml")
            .args(&["-ksp_type", "preonly", "extra.toml"]),
    ]
}

/// Rows of the table: Values that overflow (found by a fuzzing sweep).
fn overflow_rows() -> Vec<Row> {
    vec![
        // --- Values that overflow (found by the same sweep).
        check(
            "tangential_penalty_overflowing",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\ntangential_penalty = 1e300\n"),
            "interface[0].tangential_penalty",
        ),
        check(
            "penalty_growth_cap_overflowing",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty_growth = 2.0\npenalty_growth_cap = 1e300\n"),
            "interface[0].penalty_growth_cap",
        ),
        check(
            "penalty_growth_cap_infinite",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty_growth_cap = inf\n"),
            "interface[0].penalty_growth_cap",
        ),
        check(
            "tangential_penalty_growth_overflowing",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\ntangential_penalty = 1e11\npenalty_growth = 2.0\n"),
            "the tangential_penalty (1e11)",
        ),
        check(
            "penalty_growth_cap_overflowing_the_range",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty = 1e10\npenalty_growth = 2.0\npenalty_growth_cap = 1e3\n"),
            "interface[0].penalty_growth_cap = 1000",
        ),
        check(
            "frictionless_contact_penalty_above_its_bound",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty = 1e11\n"),
            "interface[0].penalty = 100000000000: must lie in [1e-6, 1e10] (a factor of E/h) for frictionless contact",
        ),
        check(
            "frictional_contact_penalty_above_its_bound",
            valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\nfriction = 0.2\npenalty = 1e4\n"),
            "interface[0].penalty = 10000: must lie in [1e-6, 1e3] (a factor of E/h) for contact with friction",
        ),
        check(
            "gradient_displacement_overflowing",
            valid_plus("[[dirichlet]]\nset = \"b.zmax\"\ncomponents = [\"z\"]\ngradient = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1e100]]\n").map(|c| c.replace("hi = [1.0, 1.0, 1.0]", "hi = [1.0, 1.0, 1e100]")),
            "dirichlet[2].gradient",
        ),
        check(
            "dirichlet_value_overflowing",
            valid_with("value = [0.01]", "value = [1e300]"),
            "dirichlet[1].value",
        ),
        check(
            "box_hi_overflowing",
            valid_with("hi = [1.0, 1.0, 1.0]", "hi = [1e300, 1.0, 1.0]"),
            "mesh[0].hi",
        ),
        check(
            "rotation_centre_overflowing",
            valid_plus("[[dirichlet]]\nset = \"b.zmin\"\ncomponents = [\"x\"]\nrotation = { axis = [1e200, 1e200, 0.0], angle = 1.0, centre = [1e300, 0.0, 0.0] }\n"),
            "centre",
        ),
    ]
}

/// Rows of the table: PETSc options and the command line.
fn option_and_command_line_rows() -> Vec<Row> {
    use Content::Text;
    vec![
        // --- PETSc options, on the command line and in a file.
        check(
            "missing_petsc_options_file",
            valid_top(r#"petsc_options = "nowhere.rc""#),
            "nowhere.rc",
        ),
        run("ksp_type_nonsense", text(VALID), "nonsense")
            .or("KSP")
            .args(&["-ksp_type", "nonsense"]),
        run("pc_type_nonsense", text(VALID), "nonsense").args(&["-pc_type", "nonsense"]),
        run("snes_rtol_nan", text(VALID), "-snes_rtol").args(&["-snes_rtol", "nan"]),
        run("snes_atol_negative", text(VALID), "-snes_atol").args(&["-snes_atol", "-1"]),
        run("snes_max_it_negative", text(VALID), "-snes_max_it -5").args(&["-snes_max_it", "-5"]),
        // Read by PETSc only at the first factorization; checked before the first step.
        run("solver_package_missing", text(VALID), "nonexistent")
            .args(&["-pc_factor_mat_solver_type", "nonexistent"]),
        run(
            "package_option_not_an_integer",
            text(VALID),
            "-mat_mumps_icntl_8 xyz",
        )
        .args(&["-mat_mumps_icntl_8", "xyz"]),
        run(
            "petscrc_bad_integer",
            valid_top(r#"petsc_options = "petscrc""#),
            "petscrc",
        )
        .or("snes_max_it")
        .file("petscrc", Text("-snes_max_it abc\n")),
        // --- The command line.
        run("out_without_value", text(VALID), "--out").args(&["--out"]),
        run("out_is_a_file", text(VALID), "results")
            .file("results", Text("not a folder\n"))
            .args(&["--out", "results"]),
    ]
}

/// What a finished row left behind.
struct Outcome {
    status: String,
    code: Option<i32>,
    stderr: String,
    out_dir: Option<PathBuf>,
}

/// Writes the row's files into a fresh folder and runs `mortar` there with a timeout.
fn execute(row: &Row) -> Result<Outcome, String> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("bad_input")
        .join(row.name);
    if dir.exists() {
        std::fs::remove_dir_all(&dir)
            .map_err(|e| format!("cannot clear {}: {e}", dir.display()))?;
    }
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let case = match &row.case {
        Some(text) => {
            std::fs::write(dir.join("case.toml"), text).map_err(|e| e.to_string())?;
            "case.toml"
        }
        None => "no_such_case.toml",
    };
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for (name, content) in &row.files {
        let to = dir.join(name);
        match content {
            Content::Text(t) => std::fs::write(&to, t).map_err(|e| e.to_string())?,
            Content::Data(from) => {
                std::fs::copy(data.join(from), &to).map_err(|e| format!("{from}: {e}"))?;
            }
        }
    }

    // Paths are relative to the row's folder, so messages never contain the row's name.
    let sub = match row.sub {
        Sub::Run => "run",
        Sub::Check => "check",
    };
    let mut args: Vec<&str> = vec![sub, case];
    let mut out_dir = None;
    if let Sub::Run = row.sub {
        match row.args.iter().position(|a| *a == "--out") {
            Some(i) => out_dir = row.args.get(i + 1).map(|d| dir.join(d)),
            None => {
                args.extend(["--out", "out"]);
                out_dir = Some(dir.join("out"));
            }
        }
    }
    args.extend(&row.args);

    let stderr_path = dir.join("stderr.txt");
    let log = |p: &Path| File::create(p).map_err(|e| format!("{}: {e}", p.display()));
    let mut child = common::mortar_command()
        .args(&args)
        .current_dir(&dir)
        .env_remove("RUST_BACKTRACE")
        .stdin(Stdio::null())
        .stdout(log(&dir.join("stdout.txt"))?)
        .stderr(log(&stderr_path)?)
        .spawn()
        .map_err(|e| format!("cannot start mortar: {e}"))?;
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!(
                "hung: killed after {} s (mortar {})",
                TIMEOUT.as_secs(),
                args.join(" ")
            ));
        }
        sleep(Duration::from_millis(20));
    };
    let stderr = std::fs::read(&stderr_path).map_err(|e| e.to_string())?;
    Ok(Outcome {
        status: status.to_string(),
        code: status.code(),
        stderr: String::from_utf8_lossy(&stderr).into_owned(),
        out_dir,
    })
}

/// Every problem with a row's outcome; empty when the row behaves.
fn problems(row: &Row, o: &Outcome) -> Vec<String> {
    let mut p = Vec::new();
    match o.code {
        None => p.push(format!("ended by a signal ({})", o.status)),
        Some(0) => p.push("exit code 0: the bad input was accepted".into()),
        Some(_) => {}
    }
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    match lines.last() {
        None => p.push("stderr is empty".into()),
        Some(last) => {
            if !last.starts_with("mortar: error:") {
                p.push("the last stderr line does not start with 'mortar: error:'".into());
            }
            if !row.culprit.iter().any(|c| last.contains(c)) {
                p.push(format!(
                    "the error does not name the culprit {:?}",
                    row.culprit
                ));
            }
        }
    }
    if lines.len() > 1 {
        p.push(format!("stderr has {} lines, not one", lines.len()));
    }
    for bad in ["panicked", "RUST_BACKTRACE"] {
        if o.stderr.contains(bad) {
            p.push(format!("stderr contains '{bad}'"));
        }
    }
    if let Some(dir) = &o.out_dir {
        for f in files_with_nan(dir) {
            p.push(format!("NaN in {}", f.display()));
        }
    }
    p
}

/// Files under `path` (a file or a folder) with a NaN token ("NaN", "nan", "-nan", ...).
fn files_with_nan(path: &Path) -> Vec<PathBuf> {
    if path.is_dir() {
        let Ok(entries) = std::fs::read_dir(path) else {
            return Vec::new();
        };
        let mut found = Vec::new();
        for e in entries.flatten() {
            found.extend(files_with_nan(&e.path()));
        }
        return found;
    }
    let Ok(bytes) = std::fs::read(path) else {
        return Vec::new();
    };
    let text = String::from_utf8_lossy(&bytes);
    let is_number_char = |c: char| c.is_ascii_alphanumeric() || "_.+-".contains(c);
    let nan = text
        .split(|c: char| !is_number_char(c))
        .any(|t| t.trim_start_matches(['+', '-']).eq_ignore_ascii_case("nan"));
    if nan {
        vec![path.to_path_buf()]
    } else {
        Vec::new()
    }
}

#[test]
fn bad_inputs_fail_with_one_clear_line() {
    let rows = rows();
    let mut names: Vec<&str> = rows.iter().map(|r| r.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), rows.len(), "row names must be unique");

    let mut failures = String::new();
    let mut failed = 0;
    for row in &rows {
        let (found, stderr) = match execute(row) {
            Ok(o) => (problems(row, &o), o.stderr),
            Err(e) => (vec![e], String::new()),
        };
        if !found.is_empty() {
            failed += 1;
            let _ = writeln!(failures, "\n=== {} ({:?})", row.name, row.sub);
            for f in &found {
                let _ = writeln!(failures, "  - {f}");
            }
            let _ = writeln!(failures, "  stderr:");
            for l in stderr.lines() {
                let _ = writeln!(failures, "    | {l}");
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{failed} of {} bad-input rows failed:{failures}",
        rows.len()
    );
}

#[test]
fn valid_scene_runs() {
    let row = run("valid_control", text(VALID), "");
    let o = execute(&row).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(o.code, Some(0), "the valid scene failed: {}", o.stderr);
    let nan = files_with_nan(
        o.out_dir
            .as_deref()
            .expect("run rows have an output folder"),
    );
    assert!(nan.is_empty(), "NaN in {nan:?}");
}

/// The ends of the documented ranges are accepted: a penalty of 1e10 E/h (the top of the range
/// of frictionless contact) with no growth, whose growth cap then bounds nothing.
#[test]
fn range_ends_are_accepted() {
    let row = check(
        "penalty_at_the_top_of_its_range",
        valid_plus("[[interface]]\nname = \"i\"\nkind = \"contact\"\nsecondary = \"b.zmax\"\nprimary = \"b.zmin\"\npenalty = 1e10\n"),
        "",
    );
    let o = execute(&row).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(o.code, Some(0), "refused: {}", o.stderr);
}
