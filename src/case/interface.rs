//! Tied and contact interfaces: their kind, their two face sets, how tractions are carried and
//! integrated, and their penalty, Uzawa and friction settings with the defaults of each kind.

use crate::contact::mortar::{traction_nodes, PalletSplit, TractionScheme};
use crate::io::case_file::InterfaceSpec;
use crate::mesh::{FaceRef, Mesh};

use super::checks::{
    check_file_name, check_penalty, check_penalty_up_to, check_positive, check_quadrature_degree,
    first_given, given, MAX_FRICTIONAL_CONTACT_PENALTY, MAX_FRICTIONLESS_CONTACT_PENALTY,
    MAX_UZAWA, PENALTY_RANGE,
};
use super::{ContactMethod, Interface, InterfaceKind, UzawaRelaxation};

/// Default tangential penalty factor of contact interfaces (see the case key
/// `tangential_penalty`): sticking about as stiff as the element layer under the node, so that
/// full Newton steps land inside a node's stick region instead of jumping over it.
const DEFAULT_TANGENTIAL_PENALTY: f64 = 1.0;
/// Default Uzawa tolerance on the slip of sticking contact nodes (see the case key
/// `uzawa_slip_tol` and docs/performance.md).
const DEFAULT_UZAWA_SLIP_TOL: f64 = 1e-6;

/// The default `uzawa_slip_motion` (see `uzawa_slip_tol` and docs/performance.md).
const DEFAULT_UZAWA_SLIP_MOTION: f64 = 3e-2;

/// Every interface, with names unique among them.
pub(super) fn build_interfaces(
    specs: &[InterfaceSpec],
    mesh: &Mesh,
) -> Result<Vec<Interface>, String> {
    let interfaces = specs
        .iter()
        .enumerate()
        .map(|(i, spec)| build_interface(spec, &format!("interface[{i}]"), mesh))
        .collect::<Result<Vec<_>, String>>()?;
    for (i, iface) in interfaces.iter().enumerate() {
        if interfaces[..i].iter().any(|o| o.name == iface.name) {
            return Err(format!(
                "interface[{i}].name = \"{}\": another interface has this name (it names \
                 output files and history columns)",
                iface.name
            ));
        }
    }
    Ok(interfaces)
}

/// Interface `key` (= `interface[i]`), checked in the order of its keys' documentation.
fn build_interface(spec: &InterfaceSpec, key: &str, mesh: &Mesh) -> Result<Interface, String> {
    check_file_name(&spec.name).map_err(|e| format!("{key}.name = \"{}\": {e}", spec.name))?;
    let kind = kind(spec, key)?;
    let secondary = side(mesh, key, &spec.secondary, "secondary")?;
    let primary = side(mesh, key, &spec.primary, "primary")?;
    if spec.secondary == spec.primary {
        return Err(format!("{key}: secondary and primary are the same set"));
    }
    let scheme = TractionScheme::from_number(spec.scheme)
        .ok_or_else(|| format!("{key}.scheme = {}: must be 1, 2 or 3", spec.scheme))?;
    let method = method(spec, key)?;
    if !matches!(spec.passes, 1 | 2) {
        return Err(format!("{key}.passes = {}: must be 1 or 2", spec.passes));
    }
    let carriers: &[(&str, &Vec<FaceRef>)] = if spec.passes == 2 {
        &[("secondary", &secondary), ("primary", &primary)]
    } else {
        &[("secondary", &secondary)]
    };
    check_carriers(mesh, key, carriers, method, scheme)?;
    let contact = kind == InterfaceKind::Contact;
    let (top, what) = match (contact, spec.friction.unwrap_or(0.0) > 0.0) {
        (false, _) => (PENALTY_RANGE.1, ""),
        (true, false) => (
            MAX_FRICTIONLESS_CONTACT_PENALTY,
            " for frictionless contact",
        ),
        (true, true) => (
            MAX_FRICTIONAL_CONTACT_PENALTY,
            " for contact with friction: above it Newton does not converge on the frictional \
             scenes",
        ),
    };
    let penalty = check_penalty_up_to(
        &format!("{key}.penalty"),
        spec.penalty.unwrap_or(if contact { 100.0 } else { 1000.0 }),
        top,
        what,
    )?;
    let uzawa_tol = check_positive(
        &format!("{key}.uzawa_tol"),
        spec.uzawa_tol.unwrap_or(if contact { 1e-6 } else { 1e-12 }),
    )?;
    check_quadrature_degree(&format!("{key}.quadrature_degree"), spec.quadrature_degree)?;
    let pallets = match spec.pallets.as_deref() {
        None => PalletSplit::default(),
        Some(name) => PalletSplit::from_name(name).ok_or_else(|| {
            format!("{key}.pallets = \"{name}\": must be \"centroid\" or \"fan\"")
        })?,
    };
    let friction = Friction::check(spec, key, penalty, method)?;
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
        friction: friction.coefficient,
        tangential_penalty: friction.tangential_penalty,
        uzawa_slip_tol: friction.uzawa_slip_tol,
        uzawa_slip_motion: friction.uzawa_slip_motion,
        uzawa_relaxation: friction.uzawa_relaxation,
        penalty_growth: friction.penalty_growth,
        penalty_growth_cap: friction.penalty_growth_cap,
    })
}

/// The interface's kind; a tied interface takes none of the contact keys.
fn kind(spec: &InterfaceSpec, key: &str) -> Result<InterfaceKind, String> {
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
        let contact_only = given!(spec; friction, tangential_penalty, uzawa_slip_tol,
            uzawa_slip_motion, uzawa_relaxation, method,
            penalty_growth, penalty_growth_cap);
        if let Some(k) = first_given(&contact_only) {
            return Err(format!("{key}.{k}: only for kind = \"contact\""));
        }
    }
    Ok(kind)
}

/// The faces of one side (`what`: "secondary" or "primary"): an existing, non-empty face set.
fn side(mesh: &Mesh, key: &str, name: &str, what: &str) -> Result<Vec<FaceRef>, String> {
    let faces = mesh
        .face_set(name)
        .map_err(|e| format!("{key}.{what}: {e}"))?;
    if faces.is_empty() {
        return Err(format!("{key}.{what}: face set '{name}' is empty"));
    }
    Ok(faces.to_vec())
}

/// How the contact measures gap and slip (default: mortar).
fn method(spec: &InterfaceSpec, key: &str) -> Result<ContactMethod, String> {
    match spec.method.as_deref() {
        None | Some("mortar") => Ok(ContactMethod::Mortar),
        Some("node_on_segment") => Ok(ContactMethod::NodeOnSegment),
        Some(m) => Err(format!(
            "{key}.method = \"{m}\": must be \"mortar\" or \"node_on_segment\""
        )),
    }
}

/// Every side that will carry tractions (`carriers`: name and faces) admits the traction
/// functions of the method and scheme on each of its face types.
fn check_carriers(
    mesh: &Mesh,
    key: &str,
    carriers: &[(&str, &Vec<FaceRef>)],
    method: ContactMethod,
    scheme: TractionScheme,
) -> Result<(), String> {
    let carried_by = method.carrier_scheme(scheme);
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
    Ok(())
}

/// The friction settings of an interface (their defaults for a tied one, which takes none).
struct Friction {
    coefficient: f64,
    tangential_penalty: f64,
    uzawa_slip_tol: f64,
    uzawa_slip_motion: f64,
    uzawa_relaxation: UzawaRelaxation,
    penalty_growth: f64,
    penalty_growth_cap: f64,
}

impl Friction {
    /// The friction coefficient, the tangential penalty and slip tolerance, the relaxation of
    /// the sticking nodes' updates (by default Aitken's for mortar, plain for `method`
    /// node-on-segment), and the penalty growth whose cap keeps both grown penalties
    /// (`penalty`, the normal one) within [`PENALTY_RANGE`].
    fn check(
        spec: &InterfaceSpec,
        key: &str,
        penalty: f64,
        method: ContactMethod,
    ) -> Result<Friction, String> {
        let coefficient = spec.friction.unwrap_or(0.0);
        if !(coefficient >= 0.0 && coefficient.is_finite()) {
            return Err(format!(
                "{key}.friction = {coefficient}: must be finite and >= 0"
            ));
        }
        let tangential_penalty = check_penalty(
            &format!("{key}.tangential_penalty"),
            spec.tangential_penalty
                .unwrap_or(DEFAULT_TANGENTIAL_PENALTY),
        )?;
        let uzawa_slip_tol = check_positive(
            &format!("{key}.uzawa_slip_tol"),
            spec.uzawa_slip_tol.unwrap_or(DEFAULT_UZAWA_SLIP_TOL),
        )?;
        let uzawa_slip_motion = check_positive(
            &format!("{key}.uzawa_slip_motion"),
            spec.uzawa_slip_motion.unwrap_or(DEFAULT_UZAWA_SLIP_MOTION),
        )?;
        let uzawa_relaxation = match spec.uzawa_relaxation.as_deref() {
            None if method == ContactMethod::NodeOnSegment => UzawaRelaxation::Plain,
            None | Some("aitken") => UzawaRelaxation::Aitken,
            Some("none") => UzawaRelaxation::Plain,
            Some(r) => {
                return Err(format!(
                    "{key}.uzawa_relaxation = \"{r}\": must be \"aitken\" or \"none\""
                ))
            }
        };
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
                "{cap_key}: with penalty_growth = {penalty_growth} the {name} ({largest:e}) may \
                 grow to {:e}, above {:e}",
                largest * penalty_growth_cap,
                PENALTY_RANGE.1
            ));
        }
        Ok(Friction {
            coefficient,
            tangential_penalty,
            uzawa_slip_tol,
            uzawa_slip_motion,
            uzawa_relaxation,
            penalty_growth,
            penalty_growth_cap,
        })
    }
}
