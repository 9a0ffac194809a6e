//! Load curves, follower pressures and body forces.

use crate::io::case_file::{BodyForceSpec, CaseFile, LoadCurveSpec, PressureSpec};
use crate::mesh::Mesh;

use super::checks::{all_within_bounds, out_of_bounds, parse_curve};
use super::materials::body_index;
use super::{BodyForce, LoadCurve, PressureLoad};

/// The scene's load curves, in the order the constraints and loads add them (they refer to
/// them by index).
#[derive(Default)]
pub(super) struct Curves(pub(super) Vec<LoadCurve>);

impl Curves {
    /// Adds the curve of `spec` (`key` names it in messages) and returns its index.
    pub(super) fn add(&mut self, spec: &LoadCurveSpec, key: String) -> Result<usize, String> {
        self.0.push(parse_curve(spec, &key)?);
        Ok(self.0.len() - 1)
    }
}

/// The follower (or dead) pressures and the body forces, their curves added in this order.
pub(super) fn build_loads(
    file: &CaseFile,
    mesh: &Mesh,
    curves: &mut Curves,
) -> Result<(Vec<PressureLoad>, Vec<BodyForce>), String> {
    let mut loads = Loads { mesh, curves };
    let pressures = each_entry(&file.pressure, "pressure", |p, key| loads.pressure(p, key))?;
    let body_forces = each_entry(&file.body_force, "body_force", |b, key| {
        loads.body_force(b, key)
    })?;
    Ok((pressures, body_forces))
}

/// `build` of every entry of the array `name`, with its key `name[i]`; the first error.
fn each_entry<S, T>(
    specs: &[S],
    name: &str,
    mut build: impl FnMut(&S, String) -> Result<T, String>,
) -> Result<Vec<T>, String> {
    specs
        .iter()
        .enumerate()
        .map(|(i, spec)| build(spec, format!("{name}[{i}]")))
        .collect()
}

/// The mesh the loads act on and the curves they add.
struct Loads<'a> {
    mesh: &'a Mesh,
    curves: &'a mut Curves,
}

impl Loads<'_> {
    /// A follower (or dead) pressure on its face set.
    fn pressure(&mut self, p: &PressureSpec, key: String) -> Result<PressureLoad, String> {
        let faces = self
            .mesh
            .face_set(&p.set)
            .map_err(|e| format!("{key}.set: {e}"))?
            .to_vec();
        if !all_within_bounds([&p.value]) {
            return Err(out_of_bounds(&format!("{key}.value")));
        }
        Ok(PressureLoad {
            set: p.set.clone(),
            faces,
            value: p.value,
            curve: self.curves.add(&p.curve, format!("{key}.curve"))?,
            follower: p.follower,
        })
    }

    /// A body force on its bodies (every body when none is named).
    fn body_force(&mut self, b: &BodyForceSpec, key: String) -> Result<BodyForce, String> {
        let bodies = match &b.body {
            Some(name) => vec![body_index(self.mesh, name)
                .ok_or_else(|| format!("{key}.body: no body '{name}'"))?],
            None => (0..self.mesh.bodies.len()).collect(),
        };
        if !all_within_bounds(&b.value) {
            return Err(out_of_bounds(&format!("{key}.value")));
        }
        Ok(BodyForce {
            bodies,
            value: b.value,
            curve: self.curves.add(&b.curve, format!("{key}.curve"))?,
        })
    }
}
