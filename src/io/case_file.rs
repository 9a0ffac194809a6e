//! The case file (`case.toml`): every key a scene may set, documented where it is declared.
//!
//! Unknown keys are rejected (`deny_unknown_fields`), so a typo is an error naming the key, not
//! a silently ignored setting. Paths are relative to the case file's folder. Validation of values
//! (E > 0, sets that exist, ...) happens in `crate::case`, which turns this file into a scene.
//!
//! ```toml
//! name = "thick_sphere"          # scene name (summary.json "case")
//! petsc_options = "petscrc"      # PETSc options file, read before the command line
//!
//! [[mesh]]                       # one or more parts, merged in order
//! body = "sphere"                # body name; generated sets are called "<body>.<set>"
//! generator = "thick_sphere_octant"
//! element = "hex20"
//! n_circ = 2
//! n_rad = 2
//! inner_radius = 1.0
//! outer_radius = 2.0
//!
//! [[material]]
//! body = "sphere"
//! model = "linear_elastic"       # or "neo_hookean"
//! young = 1000.0
//! poisson = 0.3
//!
//! [[symmetry]]
//! set = "sphere.symx"
//! normal = "x"
//!
//! [[pressure]]
//! set = "sphere.inner"
//! value = 1.0
//!
//! [steps]
//! count = 1
//! ```

use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

/// The whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Scene name, written as `case` in summary.json and naming the output files. Default: the
    /// case folder's name. Not empty, no leading `.`, no `/`, `\` or control characters.
    pub name: Option<String>,
    /// PETSc options file (relative to the case file), read before the command line so command
    /// line options win. Optional.
    pub petsc_options: Option<String>,
    /// Degree of polynomials the element quadrature integrates exactly (1..=10), for every
    /// element. Default per type: Hex8 3 (2x2x2 Gauss), Hex20 and Hex27 5 (3x3x3), Tet4 2,
    /// Tet10 4.
    pub quadrature_degree: Option<usize>,
    /// Mesh parts, merged in order into one mesh. At least one.
    pub mesh: Vec<MeshPart>,
    /// One material per body.
    #[serde(default)]
    pub material: Vec<MaterialSpec>,
    /// Prescribed displacements.
    #[serde(default)]
    pub dirichlet: Vec<DirichletSpec>,
    /// Symmetry planes: the normal displacement component is zero on the set.
    #[serde(default)]
    pub symmetry: Vec<SymmetrySpec>,
    /// Follower pressures on face sets.
    #[serde(default)]
    pub pressure: Vec<PressureSpec>,
    /// Body forces per unit reference volume.
    #[serde(default)]
    pub body_force: Vec<BodyForceSpec>,
    /// Interfaces between face sets: mesh tying or frictional contact.
    #[serde(default)]
    pub interface: Vec<InterfaceSpec>,
    /// Load stepping.
    #[serde(default)]
    pub steps: StepsSpec,
    /// Newton settings (PETSc's `-snes_*` options override them).
    #[serde(default)]
    pub newton: NewtonSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Exact solution the run is measured against (optional).
    pub verification: Option<VerificationSpec>,
    /// Checks on the run's summary metrics, `"<metric> <op> <number>"` with `op` one of `<=`,
    /// `>=`, `<`, `>`, `==` and `*` wildcards in the metric (`crate::expect`): `mortar run`
    /// prints each with its measured value and fails when one does not hold. Default: none.
    #[serde(default)]
    pub expect: Vec<String>,
}

/// One mesh part: a generator or a Gmsh file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshPart {
    /// Body name for generated parts (their sets become `<body>.<set>`). Default: `"body"`.
    /// Gmsh parts take their bodies from 3D physical groups and their set names as written in
    /// the file (`body` is refused there).
    pub body: Option<String>,
    /// `"box"`, `"beam"`, `"thick_sphere_octant"`, `"hemisphere_quarter"` or `"gmsh"`.
    pub generator: String,
    /// Element type of generated parts: `hex8`, `hex20`, `hex27`, `tet4`, `tet10`
    /// (hemisphere_quarter: hexahedra only).
    pub element: Option<String>,
    /// box, beam: elements along x, y, z.
    pub divisions: Option<[usize; 3]>,
    /// box: lower corner, within +-1e100 (as every coordinate and length of a part).
    pub lo: Option<[f64; 3]>,
    /// box: upper corner.
    pub hi: Option<[f64; 3]>,
    /// box: geometric grading per axis, the last cell's length over the first's (cells grow in
    /// a constant ratio; 1 = uniform, > 1 finer toward `lo`, < 1 finer toward `hi`), each
    /// in [1e-6, 1e6]. Default `[1, 1, 1]`.
    pub grading: Option<[f64; 3]>,
    /// box: per axis, the length from the fine end (`lo` for a grading above 1, `hi` below 1)
    /// that keeps uniform cells before they grow; `grading` is then the spacing at the coarse
    /// end over the zone's. Each in `[0, hi - lo)`, and non-zero only on a graded axis.
    /// Default `[0, 0, 0]` (no zone).
    pub grading_zone: Option<[f64; 3]>,
    /// beam: length (x), width (y), height (z), each > 0 and at most 1e100.
    pub length: Option<f64>,
    pub width: Option<f64>,
    pub height: Option<f64>,
    /// thick_sphere_octant, hemisphere_quarter: elements along each side of each of the three
    /// surface patches (hemisphere_quarter: and of its core cube).
    pub n_circ: Option<usize>,
    /// thick_sphere_octant: elements through the thickness; hemisphere_quarter: through the
    /// shell between the core cube and the sphere.
    pub n_rad: Option<usize>,
    /// thick_sphere_octant: radii, > 0 and at most 1e100.
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    /// hemisphere_quarter: the radius R. The part is the quarter `x, y >= 0` of the solid
    /// hemisphere with its pole at the origin, its centre at `(0, 0, R)` and its flat face at
    /// `z = R` (move it with `translate`); sets `<body>.sphere` (the spherical surface),
    /// `<body>.flat`, `<body>.symx` (x = 0), `<body>.symy` (y = 0). See
    /// `mesh::generate::hemisphere_quarter`.
    pub radius: Option<f64>,
    /// hemisphere_quarter: grading toward the pole, the polar-angle spacing of the surface
    /// nodes at the equator over that at the pole (in [1, 1e6]; 1 = none). Default 1.
    pub pole_grading: Option<f64>,
    /// hemisphere_quarter: the arc length from the pole (on the sphere) over which the polar
    /// spacing stays uniform (the fine cap, where the contact is) before it grows; with it,
    /// `pole_grading` is the spacing at the equator over the cap's. In `[0, 0.9 pi R / 2)`, and
    /// only with `pole_grading` > 1. Default 0: the spacing grows from the pole on.
    pub pole_zone: Option<f64>,
    /// hemisphere_quarter: grading of the shell toward the surface, the innermost layer's
    /// thickness over the outermost's (in [1, 1e6]; 1 = uniform). Default 1.
    pub radial_grading: Option<f64>,
    /// gmsh: the .msh file (format 4.1, ASCII or binary).
    pub file: Option<String>,
    /// Moves every node of the part by this vector after generation, within +-1e100. Default:
    /// none.
    pub translate: Option<[f64; 3]>,
    /// Perturbs interior nodes of a generated part by up to this fraction of the local element
    /// size (deterministic pseudo-random), to test distorted meshes. Default 0.
    #[serde(default)]
    pub distort: f64,
}

/// A material for one body.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Body name. May be omitted when the mesh has one body.
    pub body: Option<String>,
    /// `"linear_elastic"` (small strain) or `"neo_hookean"` (compressible, finite strain).
    pub model: String,
    /// Young's modulus, in [1e-100, 1e100].
    pub young: f64,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson: f64,
}

/// How a boundary value evolves with the load factor t in [0, 1] (pseudo-time).
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LoadCurveSpec {
    /// `"ramp"` (value * t, the default), `"constant"` (value at every step) or `"table"`.
    pub kind: Option<String>,
    /// For `"table"`: `[[t0, f0], [t1, f1], ...]` with increasing t; linear in between, constant
    /// outside; the value applied is value * f(t).
    pub table: Option<Vec<[f64; 2]>>,
}

/// Prescribed displacement components on a node or face set.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirichletSpec {
    /// Node set or face set name.
    pub set: String,
    /// Components fixed: any of `"x"`, `"y"`, `"z"`, each at most once.
    pub components: Vec<String>,
    /// Displacement at full load for each listed component (same order), within +-1e100.
    /// Default: zeros.
    pub value: Option<Vec<f64>>,
    /// Instead of `value`: the displacement at full load is the linear field u = G X with this
    /// gradient G (row-major 3x3, entries and the displacements they give within +-1e100),
    /// evaluated at each node (used by patch tests).
    pub gradient: Option<[[f64; 3]; 3]>,
    /// Load curve. Default: ramp.
    #[serde(default)]
    pub curve: LoadCurveSpec,
    /// A rigid rotation applied after `value`: the prescribed displacement of a node at X is
    /// `u = R(t) (X - centre + v curve(t)) + centre - X`, with v the entry's `value` (zero for
    /// the components not listed) and `R(t)` the rotation by `angle * rotation.curve(t)` about
    /// `axis` through `centre`; only the listed components are prescribed. Not with `gradient`.
    pub rotation: Option<RotationSpec>,
}

/// A prescribed rigid rotation (see `DirichletSpec::rotation`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationSpec {
    /// Rotation axis (any nonzero length).
    pub axis: [f64; 3],
    /// Angle at full load, radians (right-hand rule about `axis`), within +-1e100.
    pub angle: f64,
    /// A point on the axis, within +-1e100. Default: the origin.
    #[serde(default)]
    pub centre: [f64; 3],
    /// How the angle follows the load. Default: ramp.
    #[serde(default)]
    pub curve: LoadCurveSpec,
}

/// A symmetry plane through a set: zero displacement along `normal`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SymmetrySpec {
    /// Node set or face set on the plane.
    pub set: String,
    /// Plane normal axis: `"x"`, `"y"` or `"z"` (planes are axis-aligned).
    pub normal: String,
}

/// Follower pressure (positive compresses: it acts against the current outward normal).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSpec {
    /// Face set name.
    pub set: String,
    /// Pressure at full load, within +-1e100.
    pub value: f64,
    /// true (default): a follower load on the current face (finite strain, with its tangent);
    /// false: a dead load on the reference face (what small-strain linear theory assumes).
    #[serde(default = "yes")]
    pub follower: bool,
    /// Load curve. Default: ramp.
    #[serde(default)]
    pub curve: LoadCurveSpec,
}

/// Body force per unit reference volume.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyForceSpec {
    /// Body name. Default: every body.
    pub body: Option<String>,
    /// Force vector at full load, each entry within +-1e100.
    pub value: [f64; 3],
    /// Load curve. Default: ramp.
    #[serde(default)]
    pub curve: LoadCurveSpec,
}

/// An interface between two face sets, enforced by mortar weights (Puso, Laursen & Solberg).
///
/// ```toml
/// [[interface]]
/// name = "blocks"
/// kind = "contact"          # or "tied"
/// secondary = "lower.top"   # carries the traction unknowns
/// primary = "upper.bottom"
/// friction = 0.3            # Coulomb mu (contact only)
/// ```
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceSpec {
    /// Name, used in output file names and metric names: unique among the interfaces, not
    /// empty, no leading `.`, no `/`, `\` or control characters.
    pub name: String,
    /// `"tied"`: the two sides move together (the vector weighted-gap constraint g_A = 0, on
    /// reference weights). `"contact"`: unilateral frictional contact (Kuhn-Tucker conditions on
    /// the normalized weighted gap, Coulomb friction on the mortar slip), on current weights.
    pub kind: String,
    /// Face set of the secondary side (the paper's slave / non-mortar side: it carries the
    /// traction unknowns).
    pub secondary: String,
    /// Face set of the primary side (master / mortar side).
    pub primary: String,
    /// Traction interpolation: 1 = the face's own shape functions (refused on Tri6 and Quad8),
    /// 2 = bilinear/linear in the corner nodes, 3 = piecewise linear over the sub-segments.
    /// Default 2.
    #[serde(default = "two")]
    pub scheme: u8,
    /// 1 = one pass (the `secondary` side carries the tractions); 2 = two passes (each side in
    /// turn, contributions added). Default 1.
    #[serde(default = "one")]
    pub passes: usize,
    /// Penalty factor alpha: eps_A = alpha E / h_A with E the secondary body's Young's modulus
    /// and h_A a length at node A: tied, h_A = sqrt(a_A) (a_A the integral of node A's
    /// traction function over the whole secondary surface, reference configuration); contact,
    /// the mean of sqrt(area) of the secondary faces around A (reference configuration), so
    /// that a uniform mesh has one penalty (the penalty patch test); a contact node partly
    /// covered by the primary surface has its penalties divided by its coverage (below 5 %
    /// coverage its traction fades out: `contact::frictional`). Default 1000 for tied
    /// interfaces (one pass then needs 1-3 Uzawa augmentations) and 100 for contact. Must lie
    /// in [1e-6, 1e12] for tied interfaces, [1e-6, 1e10] for frictionless contact and
    /// [1e-6, 1e3] for contact with friction (above these Newton does not converge: the
    /// residual stalls at round-off, or the Coulomb cone switches nodes between stick and slip;
    /// docs/verification.md, "Extremes").
    pub penalty: Option<f64>,
    /// Uzawa augmentations stop when every violation is below this fraction of h_A. Tied: the
    /// gap |g_A| / a_A; default 1e-12 (the tied patch test holds to 1e-10). Contact: the
    /// penetration gh_A of every pressed node; default 1e-6.
    pub uzawa_tol: Option<f64>,
    /// Contact with friction: augmentations also go on while the slip |dsh_A| of a sticking
    /// node is above this fraction of h_A and above `uzawa_slip_motion` times the interface's
    /// motion: a floor, for an interface that hardly moves. Default 1e-6, chosen with
    /// `cases/stick_phase/study.toml` (docs/performance.md).
    pub uzawa_slip_tol: Option<f64>,
    /// Contact with friction: a sticking node's slip may be up to this fraction of the
    /// interface's tangential motion over the step (the largest tangential displacement of its
    /// pressed traction nodes since the last step; the larger of this and `uzawa_slip_tol`
    /// holds), so that the slip a penalty leaves stays small against the motion that loads the
    /// interface, whatever the motion's size against the mesh. Default 3e-2, chosen with
    /// `cases/stick_phase/study.toml` (docs/performance.md).
    pub uzawa_slip_motion: Option<f64>,
    /// Contact with friction: how the Uzawa updates of sticking nodes are relaxed: "aitken"
    /// (each update scaled by Aitken's factor from the last two, while the interface sticks
    /// whole and no node changed state; the default for mortar contact) or "none" (the plain
    /// update; the default for node-on-segment, whose Figure 7 baseline it keeps as measured).
    /// See docs/theory.md section 4 and docs/performance.md.
    pub uzawa_relaxation: Option<String>,
    /// At most this many augmentations per load step (0: plain penalty). Default 0 for two
    /// passes: on dissimilar meshes the two passes' weak conditions cannot both hold exactly,
    /// so augmenting them drives a tied interface into locking and never meets a contact
    /// tolerance (docs/performance.md); two passes are a penalty method. One pass: 50 tied, 10
    /// contact. At most 1000.
    pub uzawa_max: Option<usize>,
    /// Degree of the triangle rule on each integration pallet. Default 8 for quadratic faces,
    /// 4 for linear ones. Up to degree 8 the rules are Dunavant's symmetric ones (6, 7, 12 and
    /// 16 points for degrees 4, 5, 6 and 8; `fe::quadrature`), collapsed Gauss above.
    pub quadrature_degree: Option<usize>,
    /// How the overlap of two faces is split into integration pallets: `"centroid"` (default,
    /// docs/theory.md 3.5): one triangle per edge of the overlap polygon from its area centroid,
    /// a split that moves continuously with the faces. `"fan"`: two triangles fewer, a fan from
    /// one vertex of the polygon (chosen by where the vertices come from, not by position);
    /// the same integral where the rule is exact (affine face pairs, the patch tests) at about
    /// half the points on rectangular overlaps. The split can jump where the overlap gains or
    /// loses a vertex, and with it the quadrature error on curved faces
    /// (`contact::mortar::clip`, "Pallets"). The sliding blocks, Hertz and bending scenes use
    /// it; docs/performance.md compares the two splits.
    pub pallets: Option<String>,
    /// Contact: Coulomb friction coefficient mu >= 0. Default 0: frictionless, and then no
    /// friction work is done at all (no slip, no return map).
    pub friction: Option<f64>,
    /// Contact: how gap and slip are measured. `"mortar"` (default): the mortar weights of the
    /// paper. `"node_on_segment"`: the baseline of Hallquist, Goudreau and Benson (1985), each
    /// node of the secondary faces against its closest primary face (`contact::node_on_segment`);
    /// the same laws, penalties and Uzawa keys; `scheme`, `quadrature_degree` and `pallets` do
    /// not apply, and faces whose nodal areas are not all positive (Quad8, Tri6) are refused.
    pub method: Option<String>,
    /// Contact: tangential penalty factor alpha_T (eps_T = alpha_T E / h_A, the stiffness of
    /// sticking). Default 1: a sticking node is then about as stiff as the element layer under
    /// it. Much stiffer sticking makes full Newton steps jump over the small stick region of a
    /// node and cycle between slip in opposite directions (docs/performance.md); the slip that
    /// a sticking node keeps under penalty is removed by the Uzawa updates of one-pass
    /// interfaces. Must lie in [1e-6, 1e12].
    pub tangential_penalty: Option<f64>,
    /// Contact: after an augmentation whose worst violation is above a quarter of the previous
    /// one, both penalties are multiplied by this factor (>= 1). Default 1: no growth.
    pub penalty_growth: Option<f64>,
    /// Contact: the penalties grow at most to this multiple of their initial values (>= 1;
    /// when they grow, `penalty_growth` > 1, `penalty` and `tangential_penalty` times it at
    /// most 1e12). Default 100.
    pub penalty_growth_cap: Option<f64>,
}

fn two() -> u8 {
    2
}

/// Load stepping: the load factor goes from 0 to 1 in `count` equal steps.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepsSpec {
    /// Number of load steps. Default 1.
    #[serde(default = "one")]
    pub count: usize,
    /// How many times a step may be halved after a failed solve before the run stops. Default 6.
    /// The smallest step, `1 / count / 2^max_cuts` of the load, must be at least 1e-12 (below,
    /// the load no longer advances in floating point).
    #[serde(default = "six")]
    pub max_cuts: usize,
    /// Start each step's Newton from a load-step predictor (the step's load and prescribed
    /// displacement increments applied through a tangent: `predictor_tangent`, by default the
    /// last Newton factorization) instead of the last converged state. Default true.
    #[serde(default = "yes")]
    pub predictor: bool,
    /// The tangent the predictor solves with. `"last_newton"` (default): the factorization of
    /// the last step's last Newton iteration, reused as it is (no assembly, no factorization);
    /// it differs from the converged tangent by the effect of the last Newton correction, and
    /// the first Newton iteration of the step corrects the prediction. The first step, and a
    /// step after a cut, an unconverged step, a step whose final solve took no Newton
    /// iteration or a grown contact pattern, assemble the tangent as `"converged"` does.
    /// `"converged"`: the tangent assembled and factorized at the converged state of the last
    /// step, the consistent predictor (one more tangent assembly and factorization per step).
    /// Read only with `predictor = true`. Why `"last_newton"` is the default:
    /// docs/performance.md.
    #[serde(default = "last_newton")]
    pub predictor_tangent: String,
    /// Frictional contact: start each step with a Newton solve (at most 6 iterations) in which
    /// every pressed node sticks, then release the Coulomb law from its solution. Default
    /// false. It helps stiff sticking (a large `tangential_penalty`) converge with full Newton
    /// steps; with the default soft sticking it is not needed (docs/performance.md).
    #[serde(default)]
    pub stick_predictor: bool,
    /// Mortar contact with Uzawa multipliers: begin each step with one Newton iteration in
    /// which every node pressed at the last converged step is held bilaterally (an opening
    /// pulls it back), and a second when the first raised the residual; kept when it lowers
    /// the residual. Default true. It closes the gaps that the predictor's linearization opens
    /// in a slide, which the penalty law alone would leave to a creeping line search
    /// (docs/performance.md, "The bilateral iteration").
    #[serde(default = "yes")]
    pub bilateral_iteration: bool,
    /// What happens when a step's Newton solve does not converge and no cut is left (a failed
    /// solve is first redone with half the increment, at most `max_cuts` times; every cut is
    /// counted in `history.csv`). `"cut"` (default): the run stops. `"continue"`: the state
    /// Newton reached is accepted as the step's result, marked `converged = 0` in
    /// `history.csv` and counted in the summary (`unconverged_steps`), and the run goes on; a
    /// state outside the domain (an inverted element, NaN) still ends it.
    /// For baselines such as node-on-segment, whose failures are part of what is measured
    /// (the paper lets its two-pass node-on-segment run go on through unconverged steps).
    #[serde(default = "cut")]
    pub on_failure: String,
}

fn cut() -> String {
    "cut".into()
}

fn last_newton() -> String {
    "last_newton".into()
}

impl Default for StepsSpec {
    fn default() -> Self {
        StepsSpec {
            count: 1,
            max_cuts: 6,
            predictor: true,
            predictor_tangent: last_newton(),
            stick_predictor: false,
            bilateral_iteration: true,
            on_failure: cut(),
        }
    }
}

fn yes() -> bool {
    true
}

fn one() -> usize {
    1
}
fn six() -> usize {
    6
}

/// Newton tolerances (overridden by `-snes_rtol`, `-snes_atol`, `-snes_stol`, `-snes_max_it`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewtonSpec {
    /// Relative residual tolerance. Default 1e-10.
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Absolute residual tolerance, relative to the norm of the full external load (or of the
    /// first residual when there is none). Default 1e-10: above the round-off floor of the
    /// assembled residual (about 1e-12 of the load for quadratic elements), where Newton would
    /// otherwise stall once the predictor has already solved a linear step.
    #[serde(default = "default_atol")]
    pub atol: f64,
    /// Relative residual tolerance of the Newton solves that an Uzawa augmentation follows
    /// (with augmented contributions): those solves need only bring the state close enough
    /// for the multipliers' update, and the step's last solve meets `rtol`. Default 1e-2;
    /// `rtol` or less makes every solve meet `rtol`.
    #[serde(default = "default_augmented_rtol")]
    pub augmented_rtol: f64,
    /// Maximum Newton iterations per step. Default 25.
    #[serde(default = "default_max_it")]
    pub max_it: usize,
    /// The linear solver of the Newton steps: `"direct"` (LU through MUMPS), `"iterative"`
    /// (GMRES with algebraic multigrid and an exact solve on the interfaces' dofs), or
    /// `"auto"` (the default: direct below `direct_below` free dofs, iterative from there on).
    /// PETSc's `-ksp_type` and `-pc_type` options replace the choice.
    #[serde(default)]
    pub linear_solver: LinearSolverSpec,
    /// The free dofs from which `linear_solver = "auto"` solves iteratively. Default: the
    /// threshold measured for the mesh's elements (docs/performance.md, "The crossover by the
    /// elements' order"), `crate::solver::DIRECT_BELOW` for first-order ones,
    /// `crate::solver::DIRECT_BELOW_SECOND_ORDER` when the mesh has any second-order element,
    /// and `crate::solver::LINEAR_DIRECT_BELOW` for a linear scene (factorized once for the
    /// whole run).
    #[serde(default)]
    pub direct_below: Option<usize>,
    /// Mortar contact: a Newton update that carries nodes open at the iterate deeper than
    /// `1e-3 h_A` into the other surface is solved again, with those nodes held on the law's
    /// pressed branch at the iterate, and the second update is taken where its full step leaves
    /// the smaller residual (with full steps and `bt`; under other line searches every update
    /// is solved once). Default true. An open node has no normal stiffness in the tangent, so the first update
    /// may drive it through the other body, and a line search then creeps
    /// (docs/performance.md, "Newton updates that close nodes, solved again").
    #[serde(default = "yes")]
    pub hold_closing: bool,
    /// The iterative path with interfaces as a two-level preconditioner: the field split with
    /// the interface's dofs smoothed by point Jacobi and the bulk by unsmoothed aggregation,
    /// then a coarse correction that solves the interface exactly (the tangent projected onto
    /// the bulk multigrid's first coarse space and the interface's dofs;
    /// `-pc_composite_pcs fieldsplit,shell`). Fewer GMRES iterations, which grow far less with
    /// the mesh, at a higher cost per Newton iteration. Default: by size, on from
    /// `crate::solver::COARSE_CORRECTION_FROM` free dofs on a nonlinear scene of first-order
    /// elements and `crate::solver::COARSE_CORRECTION_FROM_SECOND_ORDER` with second-order
    /// ones, off otherwise (docs/performance.md, "The interface coarse correction");
    /// `true` or `false` forces it either way.
    #[serde(default)]
    pub coarse_correction: Option<bool>,
}

/// The linear solver a case asks for (`newton.linear_solver`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolverSpec {
    /// Chosen by the number of free dofs.
    #[default]
    Auto,
    Direct,
    Iterative,
}

impl Default for NewtonSpec {
    fn default() -> Self {
        NewtonSpec {
            rtol: default_rtol(),
            augmented_rtol: default_augmented_rtol(),
            atol: default_atol(),
            max_it: default_max_it(),
            linear_solver: LinearSolverSpec::Auto,
            direct_below: None,
            hold_closing: true,
            coarse_correction: None,
        }
    }
}

fn default_rtol() -> f64 {
    1e-10
}
fn default_augmented_rtol() -> f64 {
    1e-2
}
fn default_atol() -> f64 {
    1e-10
}
fn default_max_it() -> usize {
    25
}

/// Output settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write VTU files every this many converged steps (the last step is always written).
    /// 0 writes none. Default 1.
    #[serde(default = "one")]
    pub vtu_every: usize,
    /// Write a checkpoint every this many finished steps, and at the last finished step of
    /// the run, into `<out>/checkpoint/` (`mortar run CASE --restart DIR` goes on from it).
    /// 0 writes none. Default 0.
    #[serde(default)]
    pub checkpoint_every: usize,
    /// Sets whose reaction forces go into the history (node or face sets with constrained
    /// dofs). Default: every set named in `dirichlet` and `symmetry`.
    pub reactions: Option<Vec<String>>,
    /// Node or face sets whose mean displacement goes into the history as `track_<set>_x`,
    /// `_y`, `_z` (a beam's tip, say), each set at most once. Default: none.
    #[serde(default)]
    pub track: Vec<String>,
    /// A study file (path relative to the case file) that `mortar run` runs after the scene,
    /// into `<out>/figure/`: for a scene whose reference figure compares variants (the sliding
    /// blocks' Figure 7, six runs). `mortar run --no-figure` skips it. Default: none.
    pub figure: Option<String>,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            vtu_every: 1,
            checkpoint_every: 0,
            reactions: None,
            track: Vec::new(),
            figure: None,
        }
    }
}

/// An exact solution to measure the run against.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerificationSpec {
    /// `"lame_sphere"` (thick sphere under inner pressure; the metric `energy_error`),
    /// `"uniform_strain"` (a linear displacement field u = G X; metrics `max_displacement_error`
    /// and `max_stress_error`), `"contact_patch"` (a uniform Cauchy stress everywhere and a
    /// uniform contact pressure on every contact interface; metrics `max_rel_stress_error`,
    /// `max_rel_pressure_error` and `net_contact_force`) or `"hertz"` (a sphere pressed on a
    /// flat along the z axis (the axis x = y = 0), against Hertz's contact radius and peak
    /// pressure for the contact force of the run; metrics `rel_error_contact_radius`,
    /// `rel_error_peak_pressure`, `rel_error_hertz` (the larger), `contact_radius`,
    /// `peak_pressure`, `hertz_contact_radius`, `hertz_peak_pressure`, `contact_force`,
    /// `max_pressure`, `hertz_contact_nodes`; see `crate::verify`, "Hertz").
    pub kind: String,
    /// lame_sphere: inner and outer radius and inner pressure.
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    /// lame_sphere: the inner pressure; contact_patch: the exact contact pressure p0.
    pub pressure: Option<f64>,
    /// uniform_strain: the displacement gradient G (row-major 3x3, finite).
    pub gradient: Option<[[f64; 3]; 3]>,
    /// contact_patch: the exact Cauchy stress (row-major 3x3, finite); the scene needs a
    /// contact interface.
    pub stress: Option<[[f64; 3]; 3]>,
    /// hertz: the radius R of the sphere pressed on the flat (for two spheres, the effective
    /// radius 1/R = 1/R1 + 1/R2), > 0. Required.
    pub radius: Option<f64>,
    /// hertz: the name of the contact interface between the two bodies (one pass,
    /// frictionless). Its
    /// secondary side's nodal pressures are measured; each side's body gives E and nu to
    /// 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2. Required.
    pub interface: Option<String>,
    /// hertz: the share of the whole contact that the mesh models, in (0, 1]: 0.25 for a
    /// quarter model with symmetry planes x = 0 and y = 0, 1 for the whole. The contact force
    /// of the run is divided by it. Required.
    pub model_fraction: Option<f64>,
}

impl CaseFile {
    /// Reads a case file, lets `edit` change its TOML table (a study's variant: another
    /// refinement, another scheme; nothing for a plain read), then parses it; errors name the
    /// file and the key.
    pub fn read_edited(
        path: &Path,
        edit: impl FnOnce(&mut toml::Table) -> std::result::Result<(), String>,
    ) -> Result<CaseFile> {
        let case_err = |msg: String| Error::Case {
            file: path.to_path_buf(),
            msg,
        };
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut table: toml::Table =
            toml::from_str(&text).map_err(|e| case_err(one_line(&e.to_string())))?;
        edit(&mut table).map_err(case_err)?;
        CaseFile::deserialize(table).map_err(|e| case_err(one_line(&e.to_string())))
    }
}

/// Folds a multi-line parser message (toml shows the offending line) into one line.
pub(crate) fn one_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.chars().all(|c| c == '|' || c == '^' || c == ' '))
        .collect::<Vec<_>>()
        .join(" ")
}
