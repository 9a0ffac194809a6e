//! One material per body.

use crate::io::case_file::CaseFile;
use crate::material::Material;
use crate::mesh::Mesh;

/// The index of the body called `name`.
pub(super) fn body_index(mesh: &Mesh, name: &str) -> Option<usize> {
    mesh.bodies.iter().position(|b| b == name)
}

/// The material of each body, from the `[[material]]` entries: each names its body (or the
/// mesh has one), each body gets exactly one, and each material's constants are valid.
pub(super) fn build_materials(file: &CaseFile, mesh: &Mesh) -> Result<Vec<Material>, String> {
    let mut mats: Vec<Option<Material>> = vec![None; mesh.bodies.len()];
    for (i, m) in file.material.iter().enumerate() {
        let key = format!("material[{i}]");
        let body = match &m.body {
            Some(name) => body_index(mesh, name).ok_or_else(|| {
                format!(
                    "{key}.body: no body '{name}' (have: {})",
                    mesh.bodies.join(", ")
                )
            })?,
            None if mesh.bodies.len() == 1 => 0,
            None => {
                return Err(format!(
                    "{key}.body: required when the mesh has several bodies"
                ))
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
                return Err(format!(
                    "{key}.model = \"{other}\": must be linear_elastic or neo_hookean"
                ))
            }
        };
        mat.validate().map_err(|e| format!("{key}: {e}"))?;
        if mats[body].is_some() {
            return Err(format!(
                "{key}: body '{}' already has a material",
                mesh.bodies[body]
            ));
        }
        mats[body] = Some(mat);
    }
    mats.into_iter()
        .enumerate()
        .map(|(b, m)| m.ok_or_else(|| format!("material: body '{}' has none", mesh.bodies[b])))
        .collect()
}
