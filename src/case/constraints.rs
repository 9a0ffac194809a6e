//! The constrained dofs: symmetry planes first, then prescribed displacements (a later entry for
//! the same dof replaces an earlier one), with their rigid rotations and the sets whose
//! reactions are reported.

use std::collections::BTreeMap;

use crate::io::case_file::{CaseFile, DirichletSpec, LoadCurveSpec, RotationSpec, SymmetrySpec};
use crate::mesh::Mesh;
use crate::{within_bounds, MAX_MAGNITUDE};

use super::checks::{all_within_bounds, axis, check_entries};
use super::loads::Curves;
use super::{Constraint, Rotation};

/// The scene's constraints and what it keeps about them.
#[derive(Default)]
pub(super) struct Constraints {
    /// One constraint per constrained dof.
    pub(super) by_dof: BTreeMap<usize, Constraint>,
    /// The constrained dofs of each set, sorted (only the sets `output.reactions` names, when
    /// it names some).
    pub(super) reaction_sets: BTreeMap<String, Vec<usize>>,
    /// `(node, axis)` of every symmetry-plane constraint.
    pub(super) symmetry: Vec<(usize, usize)>,
    pub(super) rotations: Vec<Rotation>,
}

/// The constraints of the case file (the zero curve of the symmetry planes is the first
/// curve, whether or not there are planes).
pub(super) fn build_constraints(
    file: &CaseFile,
    mesh: &Mesh,
    curves: &mut Curves,
) -> Result<Constraints, String> {
    let mut c = Constraints::default();
    let zero_curve = curves.add(&LoadCurveSpec::default(), String::new())?;
    for (i, s) in file.symmetry.iter().enumerate() {
        c.add_symmetry(s, i, mesh, zero_curve)?;
    }
    for (i, d) in file.dirichlet.iter().enumerate() {
        c.add_dirichlet(d, &format!("dirichlet[{i}]"), mesh, curves)?;
    }
    for dofs in c.reaction_sets.values_mut() {
        dofs.sort_unstable();
        dofs.dedup();
    }
    if let Some(names) = &file.output.reactions {
        c.reaction_sets.retain(|k, _| names.contains(k));
        for n in names {
            if !c.reaction_sets.contains_key(n) {
                return Err(format!(
                    "output.reactions: '{n}' is not a constrained set (use a set named in dirichlet or symmetry)"
                ));
            }
        }
    }
    Ok(c)
}

impl Constraints {
    /// Constrains the dof of each constraint, and counts them for the reactions of `set` (a
    /// constrained set even when it has no nodes).
    fn constrain(&mut self, set: &str, constraints: Vec<Constraint>) {
        let dofs = self.reaction_sets.entry(set.to_string()).or_default();
        for c in constraints {
            dofs.push(c.dof);
            self.by_dof.insert(c.dof, c);
        }
    }

    /// Symmetry plane `i`: the normal component of every node of its set is zero.
    fn add_symmetry(
        &mut self,
        s: &SymmetrySpec,
        i: usize,
        mesh: &Mesh,
        zero_curve: usize,
    ) -> Result<(), String> {
        let c = axis(&s.normal)
            .ok_or_else(|| format!("symmetry[{i}].normal = \"{}\": must be x, y or z", s.normal))?;
        let nodes = mesh
            .nodes_of_set(&s.set)
            .map_err(|e| format!("symmetry[{i}].set: {e}"))?;
        self.symmetry.extend(nodes.iter().map(|&v| (v, c)));
        let constraints = nodes
            .iter()
            .map(|&v| Constraint {
                dof: 3 * v + c,
                value: 0.0,
                curve: zero_curve,
                rotation: None,
            })
            .collect();
        self.constrain(&s.set, constraints);
        Ok(())
    }

    /// A prescribed displacement (`key` = `dirichlet[i]`): its components on every node of its
    /// set, by value or by gradient, with its rigid rotation if any.
    fn add_dirichlet(
        &mut self,
        d: &DirichletSpec,
        key: &str,
        mesh: &Mesh,
        curves: &mut Curves,
    ) -> Result<(), String> {
        let nodes = mesh
            .nodes_of_set(&d.set)
            .map_err(|e| format!("{key}.set: {e}"))?;
        let comps = components(d, key)?;
        let values = values(d, key, comps.len())?;
        let curve = curves.add(&d.curve, format!("{key}.curve"))?;
        let rotation = match &d.rotation {
            None => None,
            Some(r) => {
                if d.gradient.is_some() {
                    return Err(format!("{key}: give rotation or gradient, not both"));
                }
                let mut shift = [0.0; 3];
                for (k, &c) in comps.iter().enumerate() {
                    shift[c] = values[k];
                }
                self.rotations.push(rotation(r, key, curves)?);
                Some((self.rotations.len() - 1, shift))
            }
        };
        let mut constraints = Vec::new();
        for &v in &nodes {
            for (k, &c) in comps.iter().enumerate() {
                let value = match &d.gradient {
                    Some(g) => (0..3).map(|j| g[c][j] * mesh.coords[v][j]).sum(),
                    None => values[k],
                };
                if !within_bounds(value) {
                    return Err(format!(
                        "{key}.gradient: gives node {v} the displacement {value:e}, beyond \
                         +-{MAX_MAGNITUDE:e}"
                    ));
                }
                constraints.push(Constraint {
                    dof: 3 * v + c,
                    value,
                    curve,
                    rotation,
                });
            }
        }
        self.constrain(&d.set, constraints);
        Ok(())
    }
}

/// The axes of a prescribed displacement's components: each x, y or z, at least one, none
/// twice.
fn components(d: &DirichletSpec, key: &str) -> Result<Vec<usize>, String> {
    let comps: Vec<usize> = d
        .components
        .iter()
        .map(|s| axis(s).ok_or_else(|| format!("{key}.components: \"{s}\" is not x, y or z")))
        .collect::<Result<_, String>>()?;
    if comps.is_empty() {
        return Err(format!("{key}.components: empty"));
    }
    if let Some(c) = (1..comps.len()).find(|&k| comps[..k].contains(&comps[k])) {
        return Err(format!(
            "{key}.components: \"{}\" is given twice",
            d.components[c]
        ));
    }
    Ok(comps)
}

/// The displacement of each of the `n` components at full load (zeros when only a gradient,
/// or nothing, is given), with the bounds of the values and the gradient.
fn values(d: &DirichletSpec, key: &str, n: usize) -> Result<Vec<f64>, String> {
    check_entries(
        &format!("{key}.gradient"),
        d.gradient.iter().flatten().flatten(),
    )?;
    if d.value.is_some() && d.gradient.is_some() {
        return Err(format!("{key}: give value or gradient, not both"));
    }
    let values = d.value.clone().unwrap_or_else(|| vec![0.0; n]);
    if values.len() != n {
        return Err(format!(
            "{key}.value has {} entries for {n} components",
            values.len(),
        ));
    }
    if let Some(v) = values.iter().find(|&&v| !within_bounds(v)) {
        return Err(format!(
            "{key}.value: {v} is not finite or beyond +-{MAX_MAGNITUDE:e}"
        ));
    }
    Ok(values)
}

/// The rigid rotation of a prescribed displacement: a nonzero axis (made unit), a bounded
/// angle and centre, and its curve.
fn rotation(r: &RotationSpec, key: &str, curves: &mut Curves) -> Result<Rotation, String> {
    // (Scaled by the largest entry first, so that no square overflows.)
    let largest = r.axis.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let len = largest
        * r.axis
            .iter()
            .map(|a| (a / largest).powi(2))
            .sum::<f64>()
            .sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return Err(format!("{key}.rotation.axis: must be a nonzero vector"));
    }
    if !(within_bounds(r.angle) && all_within_bounds(&r.centre)) {
        return Err(format!(
            "{key}.rotation: angle = {} and centre = {:?} must be finite and within \
             +-{MAX_MAGNITUDE:e}",
            r.angle, r.centre
        ));
    }
    Ok(Rotation {
        axis: r.axis.map(|a| a / len),
        angle: r.angle,
        centre: r.centre,
        curve: curves.add(&r.curve, format!("{key}.rotation.curve"))?,
    })
}
