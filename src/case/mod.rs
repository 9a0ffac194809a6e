//! The validated scene: a case file turned into a mesh, materials, constraints and loads.
//!
//! Every check of user input happens here, before any solve, with an error that names the key
//! (`material[1].poisson`), the set, the body or the element. `mortar check` runs exactly this.
//!
//! - [`scene`]: the validated types ([`Scene`] and what it holds);
//! - [`Scene::load`]: the case file read and turned into a scene, step by step: the mesh
//!   (`mesh`, its parts checked by `parts`), the materials (`materials`), the constraints
//!   (`constraints`), the loads and their curves (`loads`), the interfaces (`interface`), the
//!   verification (`verification`) and the run settings;
//! - `checks`: the limits of the values and the checks several of these share.

mod checks;
mod constraints;
mod interface;
mod loads;
mod materials;
mod mesh;
mod parts;
pub mod scene;
mod verification;

use std::path::{Path, PathBuf};

pub use scene::{
    BodyForce, Constraint, ContactMethod, Interface, InterfaceKind, LoadCurve, PressureLoad,
    Rotation, Scene, UzawaRelaxation, Verification,
};

use crate::error::{Error, Result};
use crate::io::case_file::CaseFile;

impl Scene {
    /// Reads and validates a case file.
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_edited(path, |_| Ok(()))
    }

    /// Reads a case file, applies `edit` to its TOML table (see `CaseFile::read_edited`), and
    /// validates the result. The first error found is returned, in the order of the steps
    /// below.
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
        let name = scene_name(&file, &dir).map_err(err)?;
        let petsc_options =
            existing_file(&dir, "petsc_options", &file.petsc_options).map_err(err)?;
        let figure = existing_file(&dir, "output.figure", &file.output.figure).map_err(err)?;
        let mesh = mesh::build_mesh(&file.mesh, &dir, &err)?;
        mesh.check()?;
        let materials = materials::build_materials(&file, &mesh).map_err(err)?;
        let mut curves = loads::Curves::default();
        let constraints = constraints::build_constraints(&file, &mesh, &mut curves).map_err(err)?;
        let (pressures, body_forces) =
            loads::build_loads(&file, &mesh, &mut curves).map_err(err)?;
        let interfaces = interface::build_interfaces(&file.interface, &mesh).map_err(err)?;
        checks::check_run_settings(&file.steps, &file.newton).map_err(err)?;
        let verification = file
            .verification
            .as_ref()
            .map(|v| verification::build_verification(v, &interfaces, &mesh, &materials))
            .transpose()
            .map_err(err)?;
        checks::check_quadrature_degree("quadrature_degree", file.quadrature_degree)
            .map_err(err)?;
        let tracked = tracked_sets(&file.output.track, &mesh).map_err(err)?;
        let expectations = crate::expect::parse_all("expect", &file.expect).map_err(err)?;
        let steps = &file.steps;
        let predictor_reuses_newton_tangent = checks::two_words(
            "steps.predictor_tangent",
            &steps.predictor_tangent,
            ["converged", "last_newton"],
        )
        .map_err(err)?;
        let continue_on_failure =
            checks::two_words("steps.on_failure", &steps.on_failure, ["cut", "continue"])
                .map_err(err)?;
        Ok(Scene {
            name,
            dir,
            petsc_options,
            figure,
            expectations,
            mesh,
            materials,
            curves: curves.0,
            constraints: constraints.by_dof.into_values().collect(),
            pressures,
            body_forces,
            interfaces,
            symmetry: constraints.symmetry,
            rotations: constraints.rotations,
            tracked,
            reaction_sets: constraints.reaction_sets,
            quadrature_degree: file.quadrature_degree,
            steps: steps.count,
            max_cuts: steps.max_cuts,
            predictor: steps.predictor,
            predictor_reuses_newton_tangent,
            stick_predictor: steps.stick_predictor,
            bilateral_iteration: steps.bilateral_iteration,
            continue_on_failure,
            newton: file.newton.clone(),
            vtu_every: file.output.vtu_every,
            checkpoint_every: file.output.checkpoint_every,
            case_digest: crate::io::checkpoint::Fnv64::of_debug(&file),
            verification,
        })
    }
}

/// The scene's name: `name` (checked: it names output files), else the case folder's name.
fn scene_name(file: &CaseFile, dir: &Path) -> std::result::Result<String, String> {
    if let Some(given) = &file.name {
        checks::check_file_name(given).map_err(|e| format!("name = \"{given}\": {e}"))?;
    }
    Ok(file.name.clone().unwrap_or_else(|| {
        dir.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into())
    }))
}

/// The file a key (`key`) names relative to the case folder, if given: it must exist.
fn existing_file(
    dir: &Path,
    key: &str,
    given: &Option<String>,
) -> std::result::Result<Option<PathBuf>, String> {
    let Some(p) = given else {
        return Ok(None);
    };
    let full = dir.join(p);
    if !full.is_file() {
        return Err(format!("{key} = \"{p}\": no such file {}", full.display()));
    }
    Ok(Some(full))
}

/// The sets whose mean displacement the history tracks, each at most once, with their nodes.
fn tracked_sets(
    names: &[String],
    mesh: &crate::mesh::Mesh,
) -> std::result::Result<Vec<(String, Vec<usize>)>, String> {
    let mut tracked = Vec::new();
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err(format!("output.track[{i}]: '{name}' is tracked twice"));
        }
        let nodes = mesh
            .nodes_of_set(name)
            .map_err(|e| format!("output.track[{i}]: {e}"))?;
        tracked.push((name.clone(), nodes.to_vec()));
    }
    Ok(tracked)
}
