//! The validated scene: what a run reads (mesh, materials, constraints, loads, interfaces,
//! settings), every value checked.

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::contact::mortar::{PalletSplit, TractionScheme};
use crate::material::Material;
use crate::mesh::{FaceRef, Mesh};

/// A value's dependence on the load factor t in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub enum LoadCurve {
    /// f(t) = t.
    Ramp,
    /// f(t) = 1.
    Constant,
    /// Piecewise linear through `(t, f)` points, constant outside.
    Table(Vec<[f64; 2]>),
}

impl LoadCurve {
    /// f(t).
    pub fn eval(&self, t: f64) -> f64 {
        match self {
            LoadCurve::Ramp => t,
            LoadCurve::Constant => 1.0,
            LoadCurve::Table(pts) => {
                if t <= pts[0][0] {
                    return pts[0][1];
                }
                for w in pts.windows(2) {
                    if t <= w[1][0] {
                        let s = (t - w[0][0]) / (w[1][0] - w[0][0]);
                        return w[0][1] + s * (w[1][1] - w[0][1]);
                    }
                }
                pts[pts.len() - 1][1]
            }
        }
    }
}

/// One constrained dof: `u[dof] = value * curve(t)`.
#[derive(Clone, Debug)]
pub struct Constraint {
    pub dof: usize,
    pub value: f64,
    pub curve: usize,
    /// A rigid rotation applied after the displacement (index into `Scene::rotations`), with
    /// the entry's whole displacement vector at full load: then
    /// `u = R(t) (X - centre + shift curve(t)) + centre - X`, component `dof % 3`.
    pub rotation: Option<(usize, [f64; 3])>,
}

/// A prescribed rigid rotation: by `angle * curve(t)` radians about `axis` (unit) through
/// `centre`.
#[derive(Clone, Debug)]
pub struct Rotation {
    pub axis: [f64; 3],
    pub angle: f64,
    pub centre: [f64; 3],
    pub curve: usize,
}

impl Constraint {
    /// The prescribed displacement of this dof at load `t` (`coords` are the reference
    /// coordinates of every node).
    pub fn value_at(
        &self,
        t: f64,
        curves: &[LoadCurve],
        rotations: &[Rotation],
        x: [f64; 3],
    ) -> f64 {
        let s = curves[self.curve].eval(t);
        match self.rotation {
            None => self.value * s,
            Some((r, shift)) => {
                let rot = &rotations[r];
                let theta = rot.angle * curves[rot.curve].eval(t);
                let p: [f64; 3] = std::array::from_fn(|i| x[i] - rot.centre[i] + shift[i] * s);
                let q = rotate(p, rot.axis, theta);
                let c = self.dof % 3;
                q[c] + rot.centre[c] - x[c]
            }
        }
    }
}

/// `v` rotated by `theta` about the unit `axis` (Rodrigues).
fn rotate(v: [f64; 3], k: [f64; 3], theta: f64) -> [f64; 3] {
    let (sin, cos) = theta.sin_cos();
    let kxv = [
        k[1] * v[2] - k[2] * v[1],
        k[2] * v[0] - k[0] * v[2],
        k[0] * v[1] - k[1] * v[0],
    ];
    let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    std::array::from_fn(|i| v[i] * cos + kxv[i] * sin + k[i] * kv * (1.0 - cos))
}

/// A follower pressure on faces.
#[derive(Clone, Debug)]
pub struct PressureLoad {
    pub set: String,
    pub faces: Vec<FaceRef>,
    pub value: f64,
    pub curve: usize,
    /// Follows the current face (true) or stays on the reference face (false).
    pub follower: bool,
}

/// A body force on the elements of some bodies.
#[derive(Clone, Debug)]
pub struct BodyForce {
    pub bodies: Vec<usize>,
    pub value: [f64; 3],
    pub curve: usize,
}

/// What an interface enforces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InterfaceKind {
    /// The sides move together (reference weights, a linear constraint).
    Tied,
    /// Unilateral frictional contact (current weights).
    Contact,
}

/// How the Uzawa updates of a contact interface's sticking nodes are relaxed
/// (`contact::frictional::relaxation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UzawaRelaxation {
    /// Aitken's factor from the last two updates, while the interface sticks whole.
    Aitken,
    /// The plain update.
    Plain,
}

/// How a contact interface measures gap and slip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactMethod {
    /// The mortar weights (the paper's method).
    Mortar,
    /// Each secondary node against its closest primary face (Hallquist et al. 1985).
    NodeOnSegment,
}

impl ContactMethod {
    /// The traction functions whose nodes carry the forces: the interface's `scheme` for
    /// mortar; for node-on-segment every node of the secondary faces with its share of the
    /// area, i.e. the faces' own shape functions (scheme 1).
    pub fn carrier_scheme(self, scheme: TractionScheme) -> TractionScheme {
        match self {
            ContactMethod::Mortar => scheme,
            ContactMethod::NodeOnSegment => TractionScheme::FaceShape,
        }
    }
}

/// A validated interface between two face sets.
#[derive(Clone, Debug)]
pub struct Interface {
    pub kind: InterfaceKind,
    pub name: String,
    /// Face set names and faces of the two sides.
    pub secondary_set: String,
    pub secondary: Vec<FaceRef>,
    pub primary_set: String,
    pub primary: Vec<FaceRef>,
    pub scheme: TractionScheme,
    /// Contact: mortar or node-on-segment (tied interfaces: mortar).
    pub method: ContactMethod,
    /// 1 or 2.
    pub passes: usize,
    /// Penalty factor alpha (eps_A = alpha E / h_A).
    pub penalty: f64,
    pub uzawa_tol: f64,
    pub uzawa_max: usize,
    pub quadrature_degree: Option<usize>,
    /// How overlaps are split into integration pallets (mortar only).
    pub pallets: PalletSplit,
    /// Contact: Coulomb coefficient mu (0 for tied interfaces).
    pub friction: f64,
    /// Contact: tangential penalty factor alpha_T.
    pub tangential_penalty: f64,
    /// Contact: Uzawa tolerance on the slip of sticking nodes (fraction of h_A).
    pub uzawa_slip_tol: f64,
    /// Contact: Uzawa tolerance on the slip of sticking nodes, as a fraction of the step's
    /// tangential motion of the node (the larger of the two tolerances holds).
    pub uzawa_slip_motion: f64,
    /// Contact: how the Uzawa updates of sticking nodes are relaxed.
    pub uzawa_relaxation: UzawaRelaxation,
    /// Contact: penalty growth factor (1 = off) and cap (multiple of the initial penalties).
    pub penalty_growth: f64,
    pub penalty_growth_cap: f64,
}

/// The exact solution a run is measured against.
#[derive(Clone, Debug)]
pub enum Verification {
    /// Lamé's thick sphere under inner pressure (docs/theory.md section 9).
    LameSphere {
        inner_radius: f64,
        outer_radius: f64,
        pressure: f64,
    },
    /// u = G X everywhere.
    UniformStrain { gradient: [[f64; 3]; 3] },
    /// Contact patch test: a uniform Cauchy stress everywhere and the contact pressure p0 at
    /// every contact node.
    ContactPatch {
        stress: [[f64; 3]; 3],
        pressure: f64,
    },
    /// Hertz: a sphere of radius `radius` pressed on a flat along the z axis, through the
    /// contact interface `interface` (see `crate::verify`, "Hertz").
    Hertz {
        /// The (effective) sphere radius R.
        radius: f64,
        /// Name of the contact interface.
        interface: String,
        /// The share of the whole contact the mesh models (0.25 for a quarter model).
        model_fraction: f64,
        /// 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 of the two sides' bodies.
        e_star: f64,
    },
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Folder of the case file.
    pub dir: PathBuf,
    /// PETSc options file, if any.
    pub petsc_options: Option<PathBuf>,
    /// The study `mortar run` runs after the scene (`output.figure`), resolved.
    pub figure: Option<PathBuf>,
    /// Checks on the run's metrics (`expect`).
    pub expectations: Vec<crate::expect::Expectation>,
    pub mesh: Mesh,
    /// Material of each body (index = body).
    pub materials: Vec<Material>,
    /// Load curves referenced by index.
    pub curves: Vec<LoadCurve>,
    /// Constrained dofs, sorted by dof, one entry each.
    pub constraints: Vec<Constraint>,
    pub pressures: Vec<PressureLoad>,
    pub body_forces: Vec<BodyForce>,
    /// Tied and contact interfaces.
    pub interfaces: Vec<Interface>,
    /// `(node, axis)` of every symmetry-plane constraint (contact normals drop those
    /// components).
    pub symmetry: Vec<(usize, usize)>,
    /// Prescribed rigid rotations (referenced by constraints).
    pub rotations: Vec<Rotation>,
    /// Sets whose mean displacement the history tracks, with their nodes.
    pub tracked: Vec<(String, Vec<usize>)>,
    /// Sets whose reactions are reported, with their constrained dofs.
    pub reaction_sets: BTreeMap<String, Vec<usize>>,
    /// Element quadrature degree, if the scene overrides the per-type default.
    pub quadrature_degree: Option<usize>,
    pub steps: usize,
    pub max_cuts: usize,
    /// Load-step predictor on (`steps.predictor`; its tangent: the next field; see `solver`).
    pub predictor: bool,
    /// The predictor reuses the last step's last Newton factorization when it can
    /// (`steps.predictor_tangent = "last_newton"`) instead of assembling the tangent at the
    /// converged state.
    pub predictor_reuses_newton_tangent: bool,
    /// Frictional steps start with a stick solve (see `solver`).
    pub stick_predictor: bool,
    /// Contact steps start with the bilateral iteration (see `solver`).
    pub bilateral_iteration: bool,
    /// An unconverged step is accepted and the run goes on (`steps.on_failure = "continue"`)
    /// instead of being cut.
    pub continue_on_failure: bool,
    pub newton: crate::io::case_file::NewtonSpec,
    pub vtu_every: usize,
    /// Checkpoint every this many finished steps and at the last (`output.checkpoint_every`;
    /// 0: none).
    pub checkpoint_every: usize,
    /// The FNV-1a hash of the case file as read (after a study's edits): a checkpoint is
    /// restarted only by the case that wrote it.
    pub case_digest: u64,
    pub verification: Option<Verification>,
}

impl Scene {
    /// True when the tangent never changes: linear-elastic materials, dead pressures only, and
    /// no contact (tied interfaces use reference weights). The solver then factorizes once per
    /// run.
    pub fn is_linear(&self) -> bool {
        self.materials
            .iter()
            .all(|m| matches!(m, Material::LinearElastic { .. }))
            && self.pressures.iter().all(|p| !p.follower)
            && self
                .interfaces
                .iter()
                .all(|i| i.kind == InterfaceKind::Tied)
    }

    /// True when a contact interface has friction (its residual is only piecewise smooth: the
    /// solver then backtracks Newton steps).
    pub fn has_friction(&self) -> bool {
        self.interfaces
            .iter()
            .any(|i| i.kind == InterfaceKind::Contact && i.friction > 0.0)
    }

    /// `constrained[3 * node + c]` for every dof.
    pub fn constrained_mask(&self) -> Vec<bool> {
        let mut m = vec![false; 3 * self.mesh.num_nodes()];
        for c in &self.constraints {
            m[c.dof] = true;
        }
        m
    }
}
