//! The exact solution a run is measured against (`[verification]`): its kind, its keys, and
//! for Hertz the interface and the E* of the bodies on its two sides.

use crate::io::case_file::VerificationSpec;
use crate::material::Material;
use crate::mesh::{FaceRef, Mesh};
use crate::{within_bounds, MAX_MAGNITUDE};

use super::checks::{check_entries, first_given, given};
use super::{Interface, InterfaceKind, Verification};

/// The verification of the case file, checked against the scene's interfaces and materials.
pub(super) fn build_verification(
    v: &VerificationSpec,
    interfaces: &[Interface],
    mesh: &Mesh,
    materials: &[Material],
) -> Result<Verification, String> {
    check_keys_of_kind(v)?;
    match v.kind.as_str() {
        "hertz" => build_hertz(v, interfaces, mesh, materials),
        "lame_sphere" => lame_sphere(v),
        "uniform_strain" => {
            let g = v
                .gradient
                .ok_or("verification: uniform_strain needs gradient")?;
            check_entries("verification.gradient", g.iter().flatten())?;
            Ok(Verification::UniformStrain { gradient: g })
        }
        "contact_patch" => contact_patch(v, interfaces),
        k => Err(format!(
            "verification.kind = \"{k}\": must be lame_sphere, uniform_strain, contact_patch or hertz"
        )),
    }
}

/// The keys of hertz and those of the other kinds do not mix (they would be ignored).
fn check_keys_of_kind(v: &VerificationSpec) -> Result<(), String> {
    let hertz_keys = given!(v; radius, interface, model_fraction);
    let other_keys = given!(v; inner_radius, outer_radius, pressure, gradient, stress);
    let foreign = if v.kind == "hertz" {
        first_given(&other_keys)
    } else {
        first_given(&hertz_keys)
    };
    match foreign {
        Some(k) => Err(format!(
            "verification.{k} does not apply to kind = \"{}\"",
            v.kind
        )),
        None => Ok(()),
    }
}

/// Lamé's thick sphere: both radii (0 < inner < outer) and the inner pressure.
fn lame_sphere(v: &VerificationSpec) -> Result<Verification, String> {
    let (a, b, p) = match (v.inner_radius, v.outer_radius, v.pressure) {
        (Some(a), Some(b), Some(p)) => (a, b, p),
        _ => {
            return Err(
                "verification: lame_sphere needs inner_radius, outer_radius, pressure".into(),
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

/// The contact patch test: a contact interface, the exact stress and a positive pressure.
fn contact_patch(v: &VerificationSpec, interfaces: &[Interface]) -> Result<Verification, String> {
    if !interfaces.iter().any(|i| i.kind == InterfaceKind::Contact) {
        return Err("verification: kind = \"contact_patch\" needs a contact interface".into());
    }
    if let Some(stress) = v.stress {
        check_entries("verification.stress", stress.iter().flatten())?;
    }
    match (v.stress, v.pressure) {
        (Some(stress), Some(pressure)) if pressure > 0.0 && within_bounds(pressure) => {
            Ok(Verification::ContactPatch { stress, pressure })
        }
        _ => Err("verification: contact_patch needs stress and pressure > 0".into()),
    }
}

/// The `hertz` verification: its keys, its interface (a one-pass contact interface) and the
/// E* of the bodies on its two sides.
fn build_hertz(
    v: &VerificationSpec,
    interfaces: &[Interface],
    mesh: &Mesh,
    materials: &[Material],
) -> Result<Verification, String> {
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
    let iface = hertz_interface(interfaces, &name)?;
    let (e1, nu1) = side_elasticity(
        mesh,
        materials,
        &name,
        &iface.secondary,
        &iface.secondary_set,
    )?;
    let (e2, nu2) = side_elasticity(mesh, materials, &name, &iface.primary, &iface.primary_set)?;
    let e_star = 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
    Ok(Verification::Hertz {
        radius,
        interface: name,
        model_fraction,
        e_star,
    })
}

/// The contact interface `name` of a Hertz verification: one pass, frictionless.
fn hertz_interface<'a>(interfaces: &'a [Interface], name: &str) -> Result<&'a Interface, String> {
    let contact = || {
        interfaces
            .iter()
            .filter(|i| i.kind == InterfaceKind::Contact)
    };
    let iface = contact().find(|i| i.name == name).ok_or_else(|| {
        let have: Vec<&str> = contact().map(|i| i.name.as_str()).collect();
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
    Ok(iface)
}

/// E and nu of the body of one side (face set `set` of interface `name`): one material.
fn side_elasticity(
    mesh: &Mesh,
    materials: &[Material],
    name: &str,
    faces: &[FaceRef],
    set: &str,
) -> Result<(f64, f64), String> {
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
}
