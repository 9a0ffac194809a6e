//! The validated scene: a case file turned into a mesh, materials, constraints and loads.
//!
//! Every check of user input happens here, before any solve, with an error that names the key
//! (`material[1].poisson`), the set, the body or the element. `mortar check` runs exactly this.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::contact::mortar::{traction_nodes, PalletSplit, TractionScheme};
use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::io::case_file::{CaseFile, LoadCurveSpec, MeshPart};
use crate::material::Material;
use crate::mesh::{FaceRef, Mesh};
use crate::{within_bounds, MAX_MAGNITUDE};

/// Largest accepted `newton.max_it`.
const MAX_NEWTON_ITS: usize = 10_000;
/// Largest accepted `steps.count`.
const MAX_STEPS: usize = 1_000_000;

/// The smallest load step that cutting may reach (`1 / steps.count / 2^max_cuts`): a margin far
/// above the round-off of the load itself (1e-16), where steps would stop advancing it, and
/// a run could never end.
const MIN_STEP: f64 = 1e-12;

/// Most Uzawa augmentations per step (`interface.uzawa_max`).
const MAX_UZAWA: usize = 1000;

/// Bounds of an interface's penalty factor (times E/h): beyond them the contact stiffness
/// swamps or vanishes against the bulk's in double precision.
const PENALTY_RANGE: (f64, f64) = (1e-6, 1e12);
/// Largest mesh a generator may build (hexahedra per part), so a typo in `divisions` is an
/// error rather than an exhausted memory.
const MAX_GENERATED_ELEMENTS: usize = 20_000_000;
/// Default tangential penalty factor of contact interfaces (see the case key
/// `tangential_penalty`): sticking about as stiff as the element layer under the node, so that
/// full Newton steps land inside a node's stick region instead of jumping over it.
const DEFAULT_TANGENTIAL_PENALTY: f64 = 1.0;
/// Default Uzawa tolerance on the slip of sticking contact nodes (see the case key
/// `uzawa_slip_tol`), chosen on the Pareto front of `cases/sliding_blocks/study_uzawa.toml`.
const DEFAULT_UZAWA_SLIP_TOL: f64 = 1e-3;

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
    /// An unconverged step is accepted and the run goes on (`steps.on_failure = "continue"`)
    /// instead of being cut.
    pub continue_on_failure: bool,
    pub newton: crate::io::case_file::NewtonSpec,
    pub vtu_every: usize,
    pub verification: Option<Verification>,
}

impl Scene {
    /// Reads and validates a case file.
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_edited(path, |_| Ok(()))
    }

    /// Reads a case file, applies `edit` to its TOML table (see `CaseFile::read_edited`), and
    /// validates the result.
    pub fn load_edited(
        path: &Path,
        edit: impl FnOnce(&mut toml::Table) -> std::result::Result<(), String>,
    ) -> Result<Scene> {
        let file = CaseFile::read_edited(path, edit)?;
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let err = |msg: String| Error::Case {
            file: path.to_path_buf(),
            msg,
        };
        if let Some(given) = &file.name {
            check_file_name(given).map_err(|e| err(format!("name = \"{given}\": {e}")))?;
        }
        let name = file.name.clone().unwrap_or_else(|| {
            dir.file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "case".into())
        });
        let petsc_options = match &file.petsc_options {
            Some(p) => {
                let full = dir.join(p);
                if !full.is_file() {
                    return Err(err(format!(
                        "petsc_options = \"{p}\": no such file {}",
                        full.display()
                    )));
                }
                Some(full)
            }
            None => None,
        };
        let figure = match &file.output.figure {
            Some(f) => {
                let full = dir.join(f);
                if !full.is_file() {
                    return Err(err(format!(
                        "output.figure = \"{f}\": no such file {}",
                        full.display()
                    )));
                }
                Some(full)
            }
            None => None,
        };
        let mesh = build_mesh(&file.mesh, &dir, &err)?;
        mesh.check()?;
        let materials = build_materials(&file, &mesh, &err)?;
        let mut curves = Vec::new();
        let mut add_curve = |c: &LoadCurveSpec, key: String| -> Result<usize> {
            curves.push(parse_curve(c, &key).map_err(err)?);
            Ok(curves.len() - 1)
        };

        // Constraints: symmetry planes first, then prescribed displacements (a later entry for
        // the same dof replaces an earlier one).
        let mut by_dof: BTreeMap<usize, Constraint> = BTreeMap::new();
        let mut reaction_sets = BTreeMap::new();
        let zero_curve = add_curve(&LoadCurveSpec::default(), String::new())?;
        let mut symmetry = Vec::new();
        let mut rotations = Vec::new();
        for (i, s) in file.symmetry.iter().enumerate() {
            let c = axis(&s.normal).ok_or_else(|| {
                err(format!(
                    "symmetry[{i}].normal = \"{}\": must be x, y or z",
                    s.normal
                ))
            })?;
            let nodes = mesh
                .nodes_of_set(&s.set)
                .map_err(|e| err(format!("symmetry[{i}].set: {e}")))?;
            let dofs: Vec<usize> = nodes.iter().map(|&v| 3 * v + c).collect();
            symmetry.extend(nodes.iter().map(|&v| (v, c)));
            for &d in &dofs {
                by_dof.insert(
                    d,
                    Constraint {
                        dof: d,
                        value: 0.0,
                        curve: zero_curve,
                        rotation: None,
                    },
                );
            }
            reaction_sets
                .entry(s.set.clone())
                .or_insert_with(Vec::new)
                .extend(dofs);
        }
        for (i, d) in file.dirichlet.iter().enumerate() {
            let key = format!("dirichlet[{i}]");
            let nodes = mesh
                .nodes_of_set(&d.set)
                .map_err(|e| err(format!("{key}.set: {e}")))?;
            let comps: Vec<usize> = d
                .components
                .iter()
                .map(|s| {
                    axis(s)
                        .ok_or_else(|| err(format!("{key}.components: \"{s}\" is not x, y or z")))
                })
                .collect::<Result<_>>()?;
            if comps.is_empty() {
                return Err(err(format!("{key}.components: empty")));
            }
            if let Some(c) = (1..comps.len()).find(|&k| comps[..k].contains(&comps[k])) {
                return Err(err(format!(
                    "{key}.components: \"{}\" is given twice",
                    d.components[c]
                )));
            }
            if !d
                .gradient
                .iter()
                .flatten()
                .flatten()
                .all(|&g| within_bounds(g))
            {
                return Err(err(format!(
                    "{key}.gradient: entries must be finite and within +-{MAX_MAGNITUDE:e}"
                )));
            }
            if d.value.is_some() && d.gradient.is_some() {
                return Err(err(format!("{key}: give value or gradient, not both")));
            }
            let values = d.value.clone().unwrap_or_else(|| vec![0.0; comps.len()]);
            if values.len() != comps.len() {
                return Err(err(format!(
                    "{key}.value has {} entries for {} components",
                    values.len(),
                    comps.len()
                )));
            }
            if let Some(v) = values.iter().find(|&&v| !within_bounds(v)) {
                return Err(err(format!(
                    "{key}.value: {v} is not finite or beyond +-{MAX_MAGNITUDE:e}"
                )));
            }
            let curve = add_curve(&d.curve, format!("{key}.curve"))?;
            let rotation = match &d.rotation {
                None => None,
                Some(r) => {
                    if d.gradient.is_some() {
                        return Err(err(format!("{key}: give rotation or gradient, not both")));
                    }
                    // (Scaled by the largest entry first, so that no square overflows.)
                    let largest = r.axis.iter().fold(0.0f64, |m, a| m.max(a.abs()));
                    let len = largest
                        * r.axis
                            .iter()
                            .map(|a| (a / largest).powi(2))
                            .sum::<f64>()
                            .sqrt();
                    if !(len > 0.0 && len.is_finite()) {
                        return Err(err(format!(
                            "{key}.rotation.axis: must be a nonzero vector"
                        )));
                    }
                    if !(within_bounds(r.angle) && r.centre.iter().all(|&c| within_bounds(c))) {
                        return Err(err(format!(
                            "{key}.rotation: angle = {} and centre = {:?} must be finite and \
                             within +-{MAX_MAGNITUDE:e}",
                            r.angle, r.centre
                        )));
                    }
                    let rcurve = add_curve(&r.curve, format!("{key}.rotation.curve"))?;
                    rotations.push(Rotation {
                        axis: r.axis.map(|a| a / len),
                        angle: r.angle,
                        centre: r.centre,
                        curve: rcurve,
                    });
                    let mut shift = [0.0; 3];
                    for (k, &c) in comps.iter().enumerate() {
                        shift[c] = values[k];
                    }
                    Some((rotations.len() - 1, shift))
                }
            };
            let mut dofs = Vec::new();
            for &v in &nodes {
                for (k, &c) in comps.iter().enumerate() {
                    let value = match &d.gradient {
                        Some(g) => (0..3).map(|j| g[c][j] * mesh.coords[v][j]).sum(),
                        None => values[k],
                    };
                    if !within_bounds(value) {
                        return Err(err(format!(
                            "{key}.gradient: gives node {v} the displacement {value:e}, beyond \
                             +-{MAX_MAGNITUDE:e}"
                        )));
                    }
                    by_dof.insert(
                        3 * v + c,
                        Constraint {
                            dof: 3 * v + c,
                            value,
                            curve,
                            rotation,
                        },
                    );
                    dofs.push(3 * v + c);
                }
            }
            reaction_sets
                .entry(d.set.clone())
                .or_insert_with(Vec::new)
                .extend(dofs);
        }
        for dofs in reaction_sets.values_mut() {
            dofs.sort_unstable();
            dofs.dedup();
        }
        if let Some(names) = &file.output.reactions {
            reaction_sets.retain(|k, _| names.contains(k));
            for n in names {
                if !reaction_sets.contains_key(n) {
                    return Err(err(format!(
                        "output.reactions: '{n}' is not a constrained set (use a set named in dirichlet or symmetry)"
                    )));
                }
            }
        }

        let mut pressures = Vec::new();
        for (i, p) in file.pressure.iter().enumerate() {
            let key = format!("pressure[{i}]");
            let faces = mesh
                .face_set(&p.set)
                .map_err(|e| err(format!("{key}.set: {e}")))?
                .to_vec();
            if !within_bounds(p.value) {
                return Err(err(format!(
                    "{key}.value is not finite or beyond +-{MAX_MAGNITUDE:e}"
                )));
            }
            let curve = add_curve(&p.curve, format!("{key}.curve"))?;
            pressures.push(PressureLoad {
                set: p.set.clone(),
                faces,
                value: p.value,
                curve,
                follower: p.follower,
            });
        }
        let mut body_forces = Vec::new();
        for (i, b) in file.body_force.iter().enumerate() {
            let key = format!("body_force[{i}]");
            let bodies = match &b.body {
                Some(name) => vec![body_index(&mesh, name)
                    .ok_or_else(|| err(format!("{key}.body: no body '{name}'")))?],
                None => (0..mesh.bodies.len()).collect(),
            };
            if !b.value.iter().all(|&v| within_bounds(v)) {
                return Err(err(format!(
                    "{key}.value is not finite or beyond +-{MAX_MAGNITUDE:e}"
                )));
            }
            let curve = add_curve(&b.curve, format!("{key}.curve"))?;
            body_forces.push(BodyForce {
                bodies,
                value: b.value,
                curve,
            });
        }
        let interfaces = file
            .interface
            .iter()
            .enumerate()
            .map(|(i, spec)| build_interface(spec, i, &mesh))
            .collect::<std::result::Result<Vec<_>, String>>()
            .map_err(err)?;
        for (i, iface) in interfaces.iter().enumerate() {
            if interfaces[..i].iter().any(|o| o.name == iface.name) {
                return Err(err(format!(
                    "interface[{i}].name = \"{}\": another interface has this name (it names \
                     output files and history columns)",
                    iface.name
                )));
            }
        }
        if file.steps.count == 0 {
            return Err(err("steps.count must be at least 1".into()));
        }
        let n = &file.newton;
        if !(n.rtol > 0.0 && n.atol > 0.0 && n.rtol.is_finite() && n.atol.is_finite()) {
            return Err(err(format!(
                "newton: rtol = {} and atol = {} must be finite and > 0",
                n.rtol, n.atol
            )));
        }
        if !(1..=MAX_NEWTON_ITS).contains(&n.max_it) {
            return Err(err(format!(
                "newton.max_it = {}: must be in 1..={MAX_NEWTON_ITS}",
                n.max_it
            )));
        }
        if file.steps.count > MAX_STEPS {
            return Err(err(format!(
                "steps.count = {}: at most {MAX_STEPS}",
                file.steps.count
            )));
        }
        let smallest_step =
            0.5f64.powi(file.steps.max_cuts.min(1100) as i32) / file.steps.count as f64;
        if smallest_step < MIN_STEP {
            return Err(err(format!(
                "steps.max_cuts = {}: with steps.count = {} the smallest step would be {smallest_step:.3e} \
                 of the load, below {MIN_STEP:e} (steps near round-off would never finish the run)",
                file.steps.max_cuts, file.steps.count
            )));
        }
        let verification = match &file.verification {
            None => None,
            Some(v) => Some(build_verification(v, &interfaces, &mesh, &materials).map_err(err)?),
        };
        if let Some(q) = file.quadrature_degree {
            if !(1..=10).contains(&q) {
                return Err(err(format!("quadrature_degree = {q}: must be in 1..=10")));
            }
        }
        let mut tracked = Vec::new();
        for (i, name) in file.output.track.iter().enumerate() {
            if file.output.track[..i].contains(name) {
                return Err(err(format!("output.track[{i}]: '{name}' is tracked twice")));
            }
            let nodes = mesh
                .nodes_of_set(name)
                .map_err(|e| err(format!("output.track[{i}]: {e}")))?;
            tracked.push((name.clone(), nodes.to_vec()));
        }
        let constraints = by_dof.into_values().collect();
        Ok(Scene {
            name,
            dir,
            petsc_options,
            figure,
            expectations: crate::expect::parse_all("expect", &file.expect).map_err(err)?,
            mesh,
            materials,
            curves,
            constraints,
            pressures,
            body_forces,
            interfaces,
            symmetry,
            rotations,
            tracked,
            reaction_sets,
            quadrature_degree: file.quadrature_degree,
            steps: file.steps.count,
            max_cuts: file.steps.max_cuts,
            predictor: file.steps.predictor,
            predictor_reuses_newton_tangent: two_words(
                "steps.predictor_tangent",
                &file.steps.predictor_tangent,
                ["converged", "last_newton"],
            )
            .map_err(err)?,
            stick_predictor: file.steps.stick_predictor,
            continue_on_failure: two_words(
                "steps.on_failure",
                &file.steps.on_failure,
                ["cut", "continue"],
            )
            .map_err(err)?,
            newton: file.newton.clone(),
            vtu_every: file.output.vtu_every,
            verification,
        })
    }

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

fn build_interface(
    spec: &crate::io::case_file::InterfaceSpec,
    i: usize,
    mesh: &Mesh,
) -> std::result::Result<Interface, String> {
    let key = format!("interface[{i}]");
    check_file_name(&spec.name).map_err(|e| format!("{key}.name = \"{}\": {e}", spec.name))?;
    let kind = match spec.kind.as_str() {
        "tied" => InterfaceKind::Tied,
        "contact" => InterfaceKind::Contact,
        k => {
            return Err(format!(
                "{key}.kind = \"{k}\": must be \"tied\" or \"contact\""
            ))
        }
    };
    if kind == InterfaceKind::Tied {
        let contact_only = [
            ("friction", spec.friction.is_some()),
            ("tangential_penalty", spec.tangential_penalty.is_some()),
            ("uzawa_slip_tol", spec.uzawa_slip_tol.is_some()),
            ("method", spec.method.is_some()),
            ("penalty_growth", spec.penalty_growth.is_some()),
            ("penalty_growth_cap", spec.penalty_growth_cap.is_some()),
        ];
        if let Some((k, _)) = contact_only.iter().find(|(_, given)| *given) {
            return Err(format!("{key}.{k}: only for kind = \"contact\""));
        }
    }
    let side = |name: &str, what: &str| -> std::result::Result<Vec<FaceRef>, String> {
        let faces = mesh
            .face_set(name)
            .map_err(|e| format!("{key}.{what}: {e}"))?;
        if faces.is_empty() {
            return Err(format!("{key}.{what}: face set '{name}' is empty"));
        }
        Ok(faces.to_vec())
    };
    let secondary = side(&spec.secondary, "secondary")?;
    let primary = side(&spec.primary, "primary")?;
    if spec.secondary == spec.primary {
        return Err(format!("{key}: secondary and primary are the same set"));
    }
    let scheme = TractionScheme::from_number(spec.scheme)
        .ok_or_else(|| format!("{key}.scheme = {}: must be 1, 2 or 3", spec.scheme))?;
    let method = match spec.method.as_deref() {
        None | Some("mortar") => ContactMethod::Mortar,
        Some("node_on_segment") => ContactMethod::NodeOnSegment,
        Some(m) => {
            return Err(format!(
                "{key}.method = \"{m}\": must be \"mortar\" or \"node_on_segment\""
            ))
        }
    };
    let carried_by = method.carrier_scheme(scheme);
    if !matches!(spec.passes, 1 | 2) {
        return Err(format!("{key}.passes = {}: must be 1 or 2", spec.passes));
    }
    // Every side that will carry tractions must admit the scheme.
    let carriers: &[(&str, &Vec<FaceRef>)] = if spec.passes == 2 {
        &[("secondary", &secondary), ("primary", &primary)]
    } else {
        &[("secondary", &secondary)]
    };
    for (what, faces) in carriers {
        let mut kinds: Vec<_> = faces.iter().map(|&f| mesh.face_type(f)).collect();
        kinds.sort();
        kinds.dedup();
        for k in kinds {
            traction_nodes(k, carried_by).map_err(|e| match method {
                ContactMethod::Mortar => format!("{key}.scheme on the {what} side: {e}"),
                ContactMethod::NodeOnSegment => format!(
                    "{key}.method = \"node_on_segment\" on the {what} side: {k:?} faces have \
                     nodal areas that are not all positive; node-on-segment needs Quad4, Quad9 \
                     or Tri3 faces"
                ),
            })?;
        }
    }
    let contact = kind == InterfaceKind::Contact;
    let positive = |name: &str, v: f64| -> std::result::Result<f64, String> {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(format!("{key}.{name} = {v}: must be finite and > 0"))
        }
    };
    let penalty = spec.penalty.unwrap_or(if contact { 100.0 } else { 1000.0 });
    if !(PENALTY_RANGE.0..=PENALTY_RANGE.1).contains(&penalty) {
        return Err(format!(
            "{key}.penalty = {penalty}: must lie in [{:e}, {:e}] (a factor of E/h)",
            PENALTY_RANGE.0, PENALTY_RANGE.1
        ));
    }
    let uzawa_tol = positive(
        "uzawa_tol",
        spec.uzawa_tol.unwrap_or(if contact { 1e-6 } else { 1e-12 }),
    )?;
    if let Some(q) = spec.quadrature_degree {
        if !(1..=10).contains(&q) {
            return Err(format!("{key}.quadrature_degree = {q}: must be in 1..=10"));
        }
    }
    let pallets = match spec.pallets.as_deref() {
        None => PalletSplit::default(),
        Some(name) => PalletSplit::from_name(name).ok_or_else(|| {
            format!("{key}.pallets = \"{name}\": must be \"centroid\" or \"fan\"")
        })?,
    };
    let friction = spec.friction.unwrap_or(0.0);
    if !(friction >= 0.0 && friction.is_finite()) {
        return Err(format!(
            "{key}.friction = {friction}: must be finite and >= 0"
        ));
    }
    let tangential_penalty = spec
        .tangential_penalty
        .unwrap_or(DEFAULT_TANGENTIAL_PENALTY);
    if !(PENALTY_RANGE.0..=PENALTY_RANGE.1).contains(&tangential_penalty) {
        return Err(format!(
            "{key}.tangential_penalty = {tangential_penalty}: must lie in [{:e}, {:e}] (a \
             factor of E/h)",
            PENALTY_RANGE.0, PENALTY_RANGE.1
        ));
    }
    let uzawa_slip_tol = positive(
        "uzawa_slip_tol",
        spec.uzawa_slip_tol.unwrap_or(DEFAULT_UZAWA_SLIP_TOL),
    )?;
    let penalty_growth = spec.penalty_growth.unwrap_or(1.0);
    if !(penalty_growth >= 1.0 && penalty_growth.is_finite()) {
        return Err(format!(
            "{key}.penalty_growth = {penalty_growth}: must be finite and >= 1"
        ));
    }
    let penalty_growth_cap = spec.penalty_growth_cap.unwrap_or(100.0);
    let cap_key = match spec.penalty_growth_cap {
        Some(_) => format!("{key}.penalty_growth_cap = {penalty_growth_cap}"),
        None => format!("{key}.penalty_growth_cap (default {penalty_growth_cap})"),
    };
    if !(penalty_growth_cap >= 1.0 && penalty_growth_cap.is_finite()) {
        return Err(format!("{cap_key}: must be finite and >= 1"));
    }
    // The cap bounds both grown penalties: it matters only when they grow.
    let (name, largest) = if tangential_penalty > penalty {
        ("tangential_penalty", tangential_penalty)
    } else {
        ("penalty", penalty)
    };
    if penalty_growth > 1.0 && largest * penalty_growth_cap > PENALTY_RANGE.1 {
        return Err(format!(
            "{cap_key}: with penalty_growth = {penalty_growth} the {name} ({largest:e}) may grow \
             to {:e}, above {:e}",
            largest * penalty_growth_cap,
            PENALTY_RANGE.1
        ));
    }
    let uzawa_max = spec.uzawa_max.unwrap_or(match (kind, spec.passes) {
        (_, 2) => 0,
        (InterfaceKind::Contact, _) => 10,
        (InterfaceKind::Tied, _) => 50,
    });
    if uzawa_max > MAX_UZAWA {
        return Err(format!(
            "{key}.uzawa_max = {uzawa_max}: at most {MAX_UZAWA} augmentations per step"
        ));
    }
    Ok(Interface {
        kind,
        name: spec.name.clone(),
        secondary_set: spec.secondary.clone(),
        secondary,
        primary_set: spec.primary.clone(),
        primary,
        scheme,
        method,
        passes: spec.passes,
        penalty,
        uzawa_tol,
        uzawa_max,
        quadrature_degree: spec.quadrature_degree,
        pallets,
        friction,
        tangential_penalty,
        uzawa_slip_tol,
        penalty_growth,
        penalty_growth_cap,
    })
}

/// A name that becomes part of output file names (the scene's, an interface's): not empty,
/// not hidden (a leading `.`), and no path separators or control characters, so that every
/// file stays inside the output folder.
fn check_file_name(name: &str) -> std::result::Result<(), String> {
    if name.is_empty() {
        Err("must not be empty (it names output files)".into())
    } else if name.starts_with('.') {
        Err("must not start with '.' (it names output files)".into())
    } else if name
        .chars()
        .any(|c| c == '/' || c == '\\' || c.is_control())
    {
        Err("must not contain '/', '\\' or control characters (it names output files)".into())
    } else {
        Ok(())
    }
}

fn axis(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

fn body_index(mesh: &Mesh, name: &str) -> Option<usize> {
    mesh.bodies.iter().position(|b| b == name)
}

fn parse_curve(c: &LoadCurveSpec, key: &str) -> std::result::Result<LoadCurve, String> {
    match (c.kind.as_deref().unwrap_or("ramp"), &c.table) {
        ("ramp", None) => Ok(LoadCurve::Ramp),
        ("constant", None) => Ok(LoadCurve::Constant),
        ("table", Some(t)) => {
            if t.len() < 2 {
                return Err(format!("{key}.table needs at least two points"));
            }
            if t.windows(2).any(|w| w[1][0] <= w[0][0])
                || t.iter().flatten().any(|v| !v.is_finite())
            {
                return Err(format!("{key}.table: t must increase and values be finite"));
            }
            Ok(LoadCurve::Table(t.clone()))
        }
        ("table", None) => Err(format!(
            "{key}: kind = \"table\" needs table = [[t, f], ...]"
        )),
        (k @ ("ramp" | "constant"), Some(_)) => {
            Err(format!("{key}: table given with kind = \"{k}\""))
        }
        (k, _) => Err(format!(
            "{key}.kind = \"{k}\": must be ramp, constant or table"
        )),
    }
}

fn build_verification(
    v: &crate::io::case_file::VerificationSpec,
    interfaces: &[Interface],
    mesh: &Mesh,
    materials: &[Material],
) -> std::result::Result<Verification, String> {
    // The keys of hertz and those of the other kinds do not mix (they would be ignored).
    let hertz_keys = [
        ("radius", v.radius.is_some()),
        ("interface", v.interface.is_some()),
        ("model_fraction", v.model_fraction.is_some()),
    ];
    let other_keys = [
        ("inner_radius", v.inner_radius.is_some()),
        ("outer_radius", v.outer_radius.is_some()),
        ("pressure", v.pressure.is_some()),
        ("gradient", v.gradient.is_some()),
        ("stress", v.stress.is_some()),
    ];
    let foreign = if v.kind == "hertz" {
        other_keys.iter().find(|(_, given)| *given)
    } else {
        hertz_keys.iter().find(|(_, given)| *given)
    };
    if let Some((k, _)) = foreign {
        return Err(format!(
            "verification.{k} does not apply to kind = \"{}\"",
            v.kind
        ));
    }
    match v.kind.as_str() {
        "hertz" => build_hertz(v, interfaces, mesh, materials),
        "lame_sphere" => {
            let (a, b, p) = match (v.inner_radius, v.outer_radius, v.pressure) {
                (Some(a), Some(b), Some(p)) => (a, b, p),
                _ => {
                    return Err(
                        "verification: lame_sphere needs inner_radius, outer_radius, pressure"
                            .into(),
                    )
                }
            };
            if !(a > 0.0 && b > a && within_bounds(b)) {
                return Err(format!("verification: radii must be finite with 0 < inner_radius < outer_radius (got {a}, {b})"));
            }
            if !within_bounds(p) {
                return Err(format!(
                    "verification.pressure = {p}: must be finite and within +-{MAX_MAGNITUDE:e}"
                ));
            }
            Ok(Verification::LameSphere {
                inner_radius: a,
                outer_radius: b,
                pressure: p,
            })
        }
        "uniform_strain" => {
            let g = v
                .gradient
                .ok_or("verification: uniform_strain needs gradient")?;
            if !g.iter().flatten().all(|&v| within_bounds(v)) {
                return Err(format!(
                    "verification.gradient: entries must be finite and within +-{MAX_MAGNITUDE:e}"
                ));
            }
            Ok(Verification::UniformStrain { gradient: g })
        }
        "contact_patch" => match (v.stress, v.pressure) {
            _ if !interfaces.iter().any(|i| i.kind == InterfaceKind::Contact) => {
                Err("verification: kind = \"contact_patch\" needs a contact interface".into())
            }
            (Some(stress), _) if !stress.iter().flatten().all(|&s| within_bounds(s)) => Err(
                format!("verification.stress: entries must be finite and within +-{MAX_MAGNITUDE:e}"),
            ),
            (Some(stress), Some(pressure)) if pressure > 0.0 && within_bounds(pressure) => {
                Ok(Verification::ContactPatch { stress, pressure })
            }
            _ => Err("verification: contact_patch needs stress and pressure > 0".into()),
        },
        k => Err(format!(
            "verification.kind = \"{k}\": must be lame_sphere, uniform_strain, contact_patch or hertz"
        )),
    }
}

/// Bounds of the generators' grading ratios (`box.grading`, `hemisphere_quarter`'s
/// `pole_grading` and `radial_grading`): beyond them the cell sizes under- or overflow.
const MIN_GRADING: f64 = 1e-6;
const MAX_GRADING: f64 = 1e6;

/// The `hertz` verification: its keys, its interface (a one-pass contact interface) and the
/// E* of the bodies on its two sides.
fn build_hertz(
    v: &crate::io::case_file::VerificationSpec,
    interfaces: &[Interface],
    mesh: &Mesh,
    materials: &[Material],
) -> std::result::Result<Verification, String> {
    let required = |name: &str| format!("verification.{name} is required for kind = \"hertz\"");
    let radius = v.radius.ok_or_else(|| required("radius"))?;
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(format!(
            "verification.radius = {radius}: must be finite and > 0"
        ));
    }
    let name = v.interface.clone().ok_or_else(|| required("interface"))?;
    let model_fraction = v.model_fraction.ok_or_else(|| required("model_fraction"))?;
    if !(model_fraction > 0.0 && model_fraction <= 1.0) {
        return Err(format!(
            "verification.model_fraction = {model_fraction}: must be in (0, 1] (0.25 for a \
             quarter model)"
        ));
    }
    let iface = interfaces
        .iter()
        .find(|i| i.name == name && i.kind == InterfaceKind::Contact)
        .ok_or_else(|| {
            let have: Vec<&str> = interfaces
                .iter()
                .filter(|i| i.kind == InterfaceKind::Contact)
                .map(|i| i.name.as_str())
                .collect();
            if have.is_empty() {
                format!("verification.interface = \"{name}\": the scene has no contact interface")
            } else {
                format!(
                    "verification.interface = \"{name}\": no contact interface of that name \
                     (have: {})",
                    have.join(", ")
                )
            }
        })?;
    if iface.passes != 1 {
        return Err(format!(
            "verification.interface = \"{name}\": hertz measures the pressures of a one-pass \
             interface (this one has {} passes)",
            iface.passes
        ));
    }
    if iface.friction != 0.0 {
        return Err(format!(
            "verification.interface = \"{name}\": Hertz's solution is frictionless, but this \
             interface has friction = {}",
            iface.friction
        ));
    }
    // E and nu of each side's body (one material per side).
    let side = |faces: &[FaceRef], set: &str| -> std::result::Result<(f64, f64), String> {
        let mut found: Option<(f64, f64)> = None;
        for f in faces {
            let m = &materials[mesh.body[f.element]];
            let en = (m.young(), m.poisson());
            match found {
                None => found = Some(en),
                Some(prev) if prev != en => {
                    return Err(format!(
                        "verification: hertz needs one material on each side of interface \
                         '{name}', but face set '{set}' spans bodies with E, nu = {prev:?} and \
                         {en:?}"
                    ))
                }
                Some(_) => {}
            }
        }
        found.ok_or_else(|| format!("verification: face set '{set}' is empty"))
    };
    let (e1, nu1) = side(&iface.secondary, &iface.secondary_set)?;
    let (e2, nu2) = side(&iface.primary, &iface.primary_set)?;
    let e_star = 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
    Ok(Verification::Hertz {
        radius,
        interface: name,
        model_fraction,
        e_star,
    })
}

fn build_materials(
    file: &CaseFile,
    mesh: &Mesh,
    err: &dyn Fn(String) -> Error,
) -> Result<Vec<Material>> {
    let mut mats: Vec<Option<Material>> = vec![None; mesh.bodies.len()];
    for (i, m) in file.material.iter().enumerate() {
        let key = format!("material[{i}]");
        let body = match &m.body {
            Some(name) => body_index(mesh, name).ok_or_else(|| {
                err(format!(
                    "{key}.body: no body '{name}' (have: {})",
                    mesh.bodies.join(", ")
                ))
            })?,
            None if mesh.bodies.len() == 1 => 0,
            None => {
                return Err(err(format!(
                    "{key}.body: required when the mesh has several bodies"
                )))
            }
        };
        let mat = match m.model.as_str() {
            "linear_elastic" => Material::LinearElastic {
                young: m.young,
                poisson: m.poisson,
            },
            "neo_hookean" => Material::NeoHookean {
                young: m.young,
                poisson: m.poisson,
            },
            other => {
                return Err(err(format!(
                    "{key}.model = \"{other}\": must be linear_elastic or neo_hookean"
                )))
            }
        };
        mat.validate().map_err(|e| err(format!("{key}: {e}")))?;
        if mats[body].is_some() {
            return Err(err(format!(
                "{key}: body '{}' already has a material",
                mesh.bodies[body]
            )));
        }
        mats[body] = Some(mat);
    }
    mats.into_iter()
        .enumerate()
        .map(|(b, m)| m.ok_or_else(|| err(format!("material: body '{}' has none", mesh.bodies[b]))))
        .collect()
}

fn build_mesh(parts: &[MeshPart], dir: &Path, err: &dyn Fn(String) -> Error) -> Result<Mesh> {
    if parts.is_empty() {
        return Err(err("mesh: at least one [[mesh]] part is required".into()));
    }
    let mut mesh = Mesh::new();
    for (i, part) in parts.iter().enumerate() {
        let mut m = build_part(part, i, dir, err)?;
        if let Some(t) = part.translate {
            for x in m.coords.iter_mut() {
                for d in 0..3 {
                    x[d] += t[d];
                }
            }
        }
        if mesh.num_elements() == 0 && mesh.coords.is_empty() {
            mesh = m;
        } else {
            mesh.merge(m);
        }
    }
    Ok(mesh)
}

fn build_part(p: &MeshPart, i: usize, dir: &Path, err: &dyn Fn(String) -> Error) -> Result<Mesh> {
    use crate::mesh::generate;
    let key = format!("mesh[{i}]");
    let need = |v: Option<f64>, name: &str| {
        v.ok_or_else(|| {
            err(format!(
                "{key}.{name} is required for generator \"{}\"",
                p.generator
            ))
        })
    };
    let positive = |v: f64, name: &str| {
        if v > 0.0 && within_bounds(v) {
            Ok(v)
        } else {
            Err(err(format!(
                "{key}.{name} = {v}: must be > 0 and at most {MAX_MAGNITUDE:e}"
            )))
        }
    };
    // The sphere generators' n_circ and n_rad: required, >= 1.
    let sphere_cells = || -> Result<(usize, usize)> {
        let cells = |v: Option<usize>, name: &str| {
            v.ok_or_else(|| {
                err(format!(
                    "{key}.{name} is required for generator \"{}\"",
                    p.generator
                ))
            })
        };
        let (nc, nr) = (cells(p.n_circ, "n_circ")?, cells(p.n_rad, "n_rad")?);
        if nc == 0 || nr == 0 {
            return Err(err(format!("{key}: n_circ and n_rad must be >= 1")));
        }
        Ok((nc, nr))
    };
    let element = || -> Result<ElementType> {
        let name = p
            .element
            .as_deref()
            .ok_or_else(|| err(format!("{key}.element is required")))?;
        ElementType::from_name(name).ok_or_else(|| {
            err(format!(
                "{key}.element = \"{name}\": must be hex8, hex20, hex27, tet4 or tet10"
            ))
        })
    };
    let divisions = || -> Result<[usize; 3]> {
        let d = p
            .divisions
            .ok_or_else(|| err(format!("{key}.divisions is required")))?;
        if d.contains(&0) {
            return Err(err(format!(
                "{key}.divisions = {d:?}: every entry must be >= 1"
            )));
        }
        Ok(d)
    };
    for (name, v) in [("lo", p.lo), ("hi", p.hi), ("translate", p.translate)] {
        if let Some(v) = v {
            if !v.iter().all(|&c| within_bounds(c)) {
                return Err(err(format!(
                    "{key}.{name} = {v:?}: must be finite and within +-{MAX_MAGNITUDE:e}"
                )));
            }
        }
    }
    if !p.distort.is_finite() {
        return Err(err(format!("{key}.distort must be finite")));
    }
    let count = match (p.generator.as_str(), p.divisions, p.n_circ, p.n_rad) {
        ("box" | "beam", Some(d), _, _) => d.iter().map(|&v| v as f64).product::<f64>(),
        ("thick_sphere_octant", _, Some(c), Some(r)) => 3.0 * (c as f64).powi(2) * r as f64,
        ("hemisphere_quarter", _, Some(c), Some(r)) => {
            (c as f64).powi(3) + 3.0 * (c as f64).powi(2) * r as f64
        }
        _ => 0.0,
    };
    if count > MAX_GENERATED_ELEMENTS as f64 {
        return Err(err(format!(
            "{key}: {count:.0} hexahedra requested; at most {MAX_GENERATED_ELEMENTS}"
        )));
    }
    check_keys_apply(p, &key).map_err(err)?;
    if p.generator != "gmsh" && p.file.is_some() {
        return Err(err(format!("{key}.file is only for generator \"gmsh\"")));
    }
    let body = p.body.clone().unwrap_or_else(|| "body".into());
    let mut mesh = match p.generator.as_str() {
        "box" => {
            let (lo, hi) = (
                p.lo.ok_or_else(|| err(format!("{key}.lo is required")))?,
                p.hi.ok_or_else(|| err(format!("{key}.hi is required")))?,
            );
            if (0..3).any(|d| hi[d] <= lo[d]) {
                return Err(err(format!(
                    "{key}: hi {hi:?} must exceed lo {lo:?} in every axis"
                )));
            }
            let grading = p.grading.unwrap_or([1.0; 3]);
            if let Some(g) = grading
                .iter()
                .find(|g| !(**g >= MIN_GRADING && **g <= MAX_GRADING))
            {
                return Err(err(format!(
                    "{key}.grading = {grading:?}: every entry must be in [{MIN_GRADING:e}, \
                     {MAX_GRADING:e}] (got {g})"
                )));
            }
            let zone = p.grading_zone.unwrap_or([0.0; 3]);
            for d in 0..3 {
                if !(zone[d] >= 0.0 && zone[d] < hi[d] - lo[d]) {
                    return Err(err(format!(
                        "{key}.grading_zone = {zone:?}: every entry must be >= 0 and below the \
                         box's length along its axis"
                    )));
                }
                if zone[d] > 0.0 && grading[d] == 1.0 {
                    return Err(err(format!(
                        "{key}.grading_zone = {zone:?}: axis {d} has a zone but no grading \
                         (grading[{d}] = 1)"
                    )));
                }
            }
            generate::zoned_box_mesh(element()?, divisions()?, lo, hi, grading, zone, &body)
        }
        "beam" => generate::beam(
            element()?,
            divisions()?,
            positive(need(p.length, "length")?, "length")?,
            positive(need(p.width, "width")?, "width")?,
            positive(need(p.height, "height")?, "height")?,
            &body,
        ),
        "thick_sphere_octant" => {
            let a = positive(need(p.inner_radius, "inner_radius")?, "inner_radius")?;
            let b = positive(need(p.outer_radius, "outer_radius")?, "outer_radius")?;
            if b <= a {
                return Err(err(format!(
                    "{key}: outer_radius {b} must exceed inner_radius {a}"
                )));
            }
            let (nc, nr) = sphere_cells()?;
            generate::thick_sphere_octant(element()?, nc, nr, a, b, &body)
        }
        "hemisphere_quarter" => {
            let r = positive(need(p.radius, "radius")?, "radius")?;
            let (nc, nr) = sphere_cells()?;
            let grading = |v: Option<f64>, name: &str| -> Result<f64> {
                let g = v.unwrap_or(1.0);
                if (1.0..=MAX_GRADING).contains(&g) {
                    Ok(g)
                } else {
                    Err(err(format!(
                        "{key}.{name} = {g}: must be in [1, {MAX_GRADING:e}]"
                    )))
                }
            };
            let pole = grading(p.pole_grading, "pole_grading")?;
            let radial = grading(p.radial_grading, "radial_grading")?;
            let kind = element()?;
            if !kind.is_hex() {
                return Err(err(format!(
                    "{key}.element = \"{}\": generator \"hemisphere_quarter\" makes hexahedra \
                     (hex8, hex20 or hex27)",
                    kind.name()
                )));
            }
            let zone = p.pole_zone.unwrap_or(0.0);
            if !(zone >= 0.0 && zone < 0.9 * std::f64::consts::FRAC_PI_2 * r) {
                return Err(err(format!(
                    "{key}.pole_zone = {zone}: must be >= 0 and below 0.9 pi R / 2 (an arc \
                     length on the sphere)"
                )));
            }
            if zone > 0.0 && pole == 1.0 {
                return Err(err(format!(
                    "{key}.pole_zone = {zone}: has no effect without pole_grading > 1"
                )));
            }
            generate::hemisphere_quarter(kind, nc, nr, r, pole, zone, radial, &body)
        }
        "gmsh" => {
            let f = p
                .file
                .as_deref()
                .ok_or_else(|| err(format!("{key}.file is required for gmsh")))?;
            return crate::io::gmsh::read_msh(&dir.join(f));
        }
        g => {
            return Err(err(format!(
                "{key}.generator = \"{g}\": must be box, beam, thick_sphere_octant, hemisphere_quarter or gmsh"
            )))
        }
    };
    prefix_sets(&mut mesh, &body);
    if p.distort != 0.0 {
        if !(0.0..0.3).contains(&p.distort) {
            return Err(err(format!(
                "{key}.distort = {}: must be in [0, 0.3)",
                p.distort
            )));
        }
        distort_interior(&mut mesh, p.distort);
    }
    Ok(mesh)
}

/// Rejects keys that the part's generator does not use (they would be silently ignored).
fn check_keys_apply(p: &MeshPart, key: &str) -> std::result::Result<(), String> {
    let given: [(&str, bool); 20] = [
        ("element", p.element.is_some()),
        ("divisions", p.divisions.is_some()),
        ("lo", p.lo.is_some()),
        ("hi", p.hi.is_some()),
        ("grading", p.grading.is_some()),
        ("grading_zone", p.grading_zone.is_some()),
        ("pole_zone", p.pole_zone.is_some()),
        ("radius", p.radius.is_some()),
        ("pole_grading", p.pole_grading.is_some()),
        ("radial_grading", p.radial_grading.is_some()),
        ("length", p.length.is_some()),
        ("width", p.width.is_some()),
        ("height", p.height.is_some()),
        ("n_circ", p.n_circ.is_some()),
        ("n_rad", p.n_rad.is_some()),
        ("inner_radius", p.inner_radius.is_some()),
        ("outer_radius", p.outer_radius.is_some()),
        ("file", p.file.is_some()),
        ("body", p.body.is_some()),
        ("distort", p.distort != 0.0),
    ];
    let allowed: &[&str] = match p.generator.as_str() {
        "box" => &[
            "body",
            "element",
            "divisions",
            "lo",
            "hi",
            "grading",
            "grading_zone",
            "distort",
        ],
        "beam" => &[
            "body",
            "element",
            "divisions",
            "length",
            "width",
            "height",
            "distort",
        ],
        "thick_sphere_octant" => &[
            "body",
            "element",
            "n_circ",
            "n_rad",
            "inner_radius",
            "outer_radius",
            "distort",
        ],
        "hemisphere_quarter" => &[
            "body",
            "element",
            "n_circ",
            "n_rad",
            "radius",
            "pole_grading",
            "pole_zone",
            "radial_grading",
            "distort",
        ],
        "gmsh" => &["file"],
        _ => return Ok(()), // the unknown generator is reported by the caller
    };
    match given.iter().find(|(k, set)| *set && !allowed.contains(k)) {
        Some((k, _)) => Err(format!(
            "{key}.{k} does not apply to generator \"{}\" (it takes: {})",
            p.generator,
            allowed.join(", ")
        )),
        None => Ok(()),
    }
}

/// Renames generated sets `s` to `<body>.s`.
fn prefix_sets(mesh: &mut Mesh, body: &str) {
    let rename = |m: &mut BTreeMap<String, Vec<_>>| {
        *m = std::mem::take(m)
            .into_iter()
            .map(|(k, v)| (format!("{body}.{k}"), v))
            .collect();
    };
    rename(&mut mesh.node_sets);
    let fs = std::mem::take(&mut mesh.face_sets);
    mesh.face_sets = fs
        .into_iter()
        .map(|(k, v)| (format!("{body}.{k}"), v))
        .collect();
    rename(&mut mesh.element_sets);
}

/// Distorts a generated part: every corner (vertex) node that lies in no node set (the interior)
/// moves by a deterministic pseudo-random vector of length up to `amount` times the shortest
/// element edge; every other interior node (mid-edge, face and centre nodes of quadratic
/// elements) moves by the motion of its element's corners interpolated at its parametric
/// position, plus a quarter of that random amount. Moving higher-order nodes with their corners
/// keeps elements valid and neighbours consistent (an edge node follows only its edge's corners).
fn distort_interior(mesh: &mut Mesh, amount: f64) {
    let n = mesh.num_nodes();
    let mut on_set = vec![false; n];
    for nodes in mesh.node_sets.values() {
        for &v in nodes {
            on_set[v] = true;
        }
    }
    let h = shortest_edge(mesh);
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let noise: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let d = [rng.next(), rng.next(), rng.next()];
            d.map(|c| amount * h * c / 3f64.sqrt())
        })
        .collect();
    // Vertex motion first.
    let mut is_vertex = vec![false; n];
    for e in 0..mesh.num_elements() {
        let k = mesh.types[e].num_corners();
        for &v in &mesh.element_nodes(e)[..k] {
            is_vertex[v] = true;
        }
    }
    let motion: Vec<[f64; 3]> = (0..n)
        .map(|v| {
            if is_vertex[v] && !on_set[v] {
                noise[v]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    // Higher-order nodes follow their corners.
    let mut placed = vec![false; n];
    let mut shift = motion.clone();
    for e in 0..mesh.num_elements() {
        let kind = mesh.types[e];
        let linear = if kind.is_hex() {
            ElementType::Hex8
        } else {
            ElementType::Tet4
        };
        let params = kind.node_coords();
        let nodes = mesh.element_nodes(e).to_vec();
        let corners = &nodes[..kind.num_corners()];
        let mut nl = vec![0.0; linear.num_nodes()];
        for (a, &v) in nodes.iter().enumerate().skip(kind.num_corners()) {
            if on_set[v] || placed[v] {
                continue;
            }
            placed[v] = true;
            linear.shape(params[a], &mut nl);
            for d in 0..3 {
                let follow: f64 = corners
                    .iter()
                    .zip(&nl)
                    .map(|(&c, w)| w * motion[c][d])
                    .sum();
                shift[v][d] = follow + 0.25 * noise[v][d];
            }
        }
    }
    for (x, d) in mesh.coords.iter_mut().zip(&shift) {
        for k in 0..3 {
            x[k] += d[k];
        }
    }
}

/// The shortest corner-to-corner element edge.
fn shortest_edge(mesh: &Mesh) -> f64 {
    let mut h = f64::INFINITY;
    for e in 0..mesh.num_elements() {
        let en = mesh.element_nodes(e);
        for edge in mesh.types[e].edges() {
            let (a, b) = (mesh.coords[en[edge[0]]], mesh.coords[en[edge[1]]]);
            let l = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            h = h.min(l);
        }
    }
    h
}

/// xorshift64*: the same sequence on every rank and platform.
struct XorShift(u64);

impl XorShift {
    /// A number in [-1, 1).
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A key that takes one of two words: false for the first, true for the second, and otherwise
/// the one-line message naming the key and both words.
fn two_words(key: &str, value: &str, [no, yes]: [&str; 2]) -> Result<bool, String> {
    match value {
        v if v == no => Ok(false),
        v if v == yes => Ok(true),
        other => Err(format!(
            "{key} = \"{other}\": must be \"{no}\" or \"{yes}\""
        )),
    }
}
