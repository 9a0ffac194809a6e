//! The bulk of the solids as a contribution to the discrete model ([`crate::model`]).
//!
//! The residual is `F(u) = f_int(u) - f_ext(u, t)`: internal forces of the elements this rank
//! owns ([`super::internal_force`]), minus follower pressures on their faces and body forces, at
//! the full displacement (free dofs from the Newton iterate, constrained dofs from the load
//! curves). The tangent is `dF/du`: `K_int - K_pressure` (the follower pressure's tangent is
//! nonsymmetric). Element and face blocks go to the sinks over the element's (face's) nodes.
//!
//! Inverted elements do not stop an evaluation half-way (that would leave other ranks waiting
//! in the collective assembly): the element is skipped, the evaluation completes, and the
//! lowest inverted element is returned for the caller to agree on over ranks.

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;
use nalgebra::DMatrix;

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{Error, Result};
use crate::fe::{quadrature::Rule2, FaceType};
use crate::model::{
    CellField, Contribution, DomainIssue, ForceSink, Inverted, Output, State, TangentSink,
};

use super::{element_stress, ElementGeometry};

/// A face carrying a pressure, on an element of this rank.
struct LoadedFace {
    nodes: Vec<usize>,
    kind: FaceType,
    load: usize,
}

/// Precomputed element data of this rank and the loads on it.
pub struct Bulk {
    /// (global element index, geometry) for each local element.
    elements: Vec<(usize, ElementGeometry)>,
    faces: Vec<LoadedFace>,
    face_rules: Vec<(FaceType, Rule2)>,
    /// Elements with a node whose rows this rank owns: the element blocks of its rows.
    pattern_elements: Vec<usize>,
    /// Nodes of this rank's elements, ascending.
    local_nodes: Vec<usize>,
}

impl Bulk {
    /// Precomputes the reference geometry of this rank's elements.
    pub fn new(scene: &Scene, dofs: &DofMap) -> Result<Bulk> {
        let mesh = &scene.mesh;
        let mut rules = std::collections::BTreeMap::new();
        let mut elements = Vec::with_capacity(dofs.local_elements.len());
        for &e in &dofs.local_elements {
            let kind = mesh.types[e];
            let rule = rules.entry(kind).or_insert_with(|| {
                kind.quadrature(
                    scene
                        .quadrature_degree
                        .unwrap_or(kind.default_quadrature_degree()),
                )
            });
            let geom =
                ElementGeometry::new(kind, rule, &mesh.element_coords(e)).map_err(|inv| {
                    Error::Mesh(format!(
                        "element {e} ({}) is inverted: {}",
                        kind.name(),
                        inv.describe(rule.points.len())
                    ))
                })?;
            elements.push((e, geom));
        }
        let face_rules = FaceType::ALL
            .iter()
            .map(|&ft| (ft, ft.quadrature(ft.default_quadrature_degree())))
            .collect();
        let pattern_elements = (0..mesh.num_elements())
            .filter(|&e| {
                mesh.element_nodes(e)
                    .iter()
                    .any(|&n| dofs.node_owner[n] == dofs.rank)
            })
            .collect();
        Ok(Bulk {
            elements,
            faces: loaded_faces(scene, dofs),
            face_rules,
            pattern_elements,
            local_nodes: dofs.local_nodes.clone(),
        })
    }

    fn face_rule(&self, ft: FaceType) -> &Rule2 {
        &self
            .face_rules
            .iter()
            .find(|(t, _)| *t == ft)
            .expect("a rule for every face type")
            .1
    }

    /// The internal force (and tangent into `ke`) of local element `e` at `u`, minus its body
    /// forces, into `fe`; the determinant of an inverted element as the error.
    fn element_force(
        &self,
        at: &State,
        (e, geom): (usize, &ElementGeometry),
        ue: &mut Vec<[f64; 3]>,
        fe: &mut Vec<f64>,
        ke: Option<&mut DMatrix<f64>>,
    ) -> std::result::Result<(), f64> {
        let scene = at.scene;
        let nodes = scene.mesh.element_nodes(e);
        gather_nodes(at.u, nodes, ue);
        fe.resize(3 * nodes.len(), 0.0);
        let mat = &scene.materials[scene.mesh.body[e]];
        super::internal_force(geom, mat, ue, fe, ke)?;
        Ok(())
    }

    /// `f_int - f_ext` of every local element (with its body forces), then of every loaded
    /// face, into `out`.
    fn forces(&self, at: &State, out: &mut dyn ForceSink) -> Result<Option<DomainIssue>> {
        let mut inverted = None;
        let (mut fe, mut ue) = (Vec::new(), Vec::new());
        for (e, geom) in &self.elements {
            if let Err(det) = self.element_force(at, (*e, geom), &mut ue, &mut fe, None) {
                inverted.get_or_insert(Inverted { element: *e, det });
                continue;
            }
            subtract_body_forces(at, *e, geom, &mut fe);
            out.add_forces(at.scene.mesh.element_nodes(*e), &fe)?;
        }
        for face in &self.faces {
            let (x, p) = face_state(at, face);
            fe.resize(3 * face.nodes.len(), 0.0);
            super::follower_pressure(face.kind, self.face_rule(face.kind), &x, p, &mut fe, None);
            fe.iter_mut().for_each(|v| *v = -*v);
            out.add_forces(&face.nodes, &fe)?;
        }
        Ok(inverted.map(DomainIssue::Inverted))
    }

    /// The verification figures of the scene over this rank's elements, reduced over ranks.
    fn verification_metrics(&self, at: &State, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        let local = crate::verify::local_figures(at.scene, &self.elements, &self.local_nodes, at.u);
        let reduce = |pairs: &[(&'static str, f64)], op: SystemOperation| {
            let vals: Vec<f64> = pairs.iter().map(|p| p.1).collect();
            let mut out = vec![0.0; vals.len()];
            world.all_reduce_into(&vals[..], &mut out[..], op);
            pairs
                .iter()
                .map(|p| p.0)
                .zip(out)
                .collect::<std::collections::BTreeMap<_, _>>()
        };
        let sums = reduce(&local.sums, SystemOperation::sum());
        let maxima = reduce(&local.maxima, SystemOperation::max());
        crate::verify::metrics(&sums, &maxima)
    }
}

impl Contribution for Bulk {
    fn couplings(&self, at: &State, couple: &mut dyn FnMut(&[usize])) {
        for &e in &self.pattern_elements {
            couple(at.scene.mesh.element_nodes(e));
        }
    }

    fn residual(&self, at: &State, out: &mut dyn ForceSink) -> Result<Option<DomainIssue>> {
        self.forces(at, out)
    }

    fn jacobian(&self, at: &State, out: &mut dyn TangentSink) -> Result<Option<DomainIssue>> {
        let mut inverted = None;
        let (mut fe, mut ue) = (Vec::new(), Vec::new());
        let mut ke = DMatrix::zeros(0, 0);
        for (e, geom) in &self.elements {
            if let Err(det) = self.element_force(at, (*e, geom), &mut ue, &mut fe, Some(&mut ke)) {
                inverted.get_or_insert(Inverted { element: *e, det });
                continue;
            }
            // nalgebra is column-major; the sinks take row-major. The element tangent is
            // symmetric but transposed anyway so that a nonsymmetric law stays right.
            let nodes = at.scene.mesh.element_nodes(*e);
            out.add_block(nodes, nodes, ke.transpose().as_slice())?;
        }
        for face in &self.faces {
            if !at.scene.pressures[face.load].follower {
                continue;
            }
            let (x, p) = face_state(at, face);
            fe.resize(3 * face.nodes.len(), 0.0);
            let rule = self.face_rule(face.kind);
            super::follower_pressure(face.kind, rule, &x, p, &mut fe, Some(&mut ke));
            // F = f_int - f_ext: the pressure's contribution to dF/du is -d f_ext / dx.
            out.add_block(&face.nodes, &face.nodes, (-ke.transpose()).as_slice())?;
        }
        Ok(inverted.map(DomainIssue::Inverted))
    }

    fn output(&self, at: &State, _world: &SimpleCommunicator) -> Vec<Output> {
        let mesh = &at.scene.mesh;
        let (mut stress, mut mises) = (Vec::new(), Vec::new());
        let mut ue = Vec::new();
        for (e, geom) in &self.elements {
            gather_nodes(at.u, mesh.element_nodes(*e), &mut ue);
            let (s, vm) = element_stress(geom, &at.scene.materials[mesh.body[*e]], &ue);
            stress.extend(s.transpose().iter().copied());
            mises.push(vm);
        }
        vec![Output::Volume {
            elements: self.elements.iter().map(|(e, _)| *e).collect(),
            fields: vec![
                CellField::new("cauchy_stress", 9, stress),
                CellField::new("von_mises", 1, mises),
            ],
        }]
    }

    fn metrics(&self, at: &State, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        self.verification_metrics(at, world)
    }
}

/// The faces of every pressure load on this rank's elements.
fn loaded_faces(scene: &Scene, dofs: &DofMap) -> Vec<LoadedFace> {
    let mut faces = Vec::new();
    for (load, p) in scene.pressures.iter().enumerate() {
        for f in p
            .faces
            .iter()
            .filter(|f| dofs.element_rank[f.element] == dofs.rank)
        {
            faces.push(LoadedFace {
                nodes: scene.mesh.face_nodes(*f),
                kind: scene.mesh.face_type(*f),
                load,
            });
        }
    }
    faces
}

/// Subtracts the consistent body forces of element `e` at load factor `at.t` from `fe`.
fn subtract_body_forces(at: &State, e: usize, geom: &ElementGeometry, fe: &mut [f64]) {
    // The consistent load is linear in b: sum the body's forces, integrate once, on the stack
    // (this runs for every element in every residual).
    let scene = at.scene;
    let body = scene.mesh.body[e];
    let mut v = [0.0; 3];
    let mut any = false;
    for b in scene
        .body_forces
        .iter()
        .filter(|b| b.bodies.contains(&body))
    {
        let s = scene.curves[b.curve].eval(at.t);
        for (vc, bc) in v.iter_mut().zip(b.value) {
            *vc += bc * s;
        }
        any = true;
    }
    if !any {
        return;
    }
    let mut buffer = [0.0; 3 * super::MAX_NODES];
    let fb = &mut buffer[..fe.len()];
    super::body_force(geom, v, fb);
    fe.iter_mut().zip(fb.iter()).for_each(|(a, b)| *a -= b);
}

/// Coordinates of a loaded face (current for a follower load, reference for a dead load) and
/// its pressure at the load factor.
fn face_state(at: &State, face: &LoadedFace) -> (Vec<[f64; 3]>, f64) {
    let load = &at.scene.pressures[face.load];
    let s = if load.follower { 1.0 } else { 0.0 };
    let x = face
        .nodes
        .iter()
        .map(|&v| {
            let x0 = at.scene.mesh.coords[v];
            [
                x0[0] + s * at.u[3 * v],
                x0[1] + s * at.u[3 * v + 1],
                x0[2] + s * at.u[3 * v + 2],
            ]
        })
        .collect();
    (x, load.value * at.scene.curves[load.curve].eval(at.t))
}

/// Copies the displacements of `nodes` out of the dof-indexed `u`.
pub fn gather_nodes(u: &[f64], nodes: &[usize], out: &mut Vec<[f64; 3]>) {
    out.clear();
    out.extend(
        nodes
            .iter()
            .map(|&v| [u[3 * v], u[3 * v + 1], u[3 * v + 2]]),
    );
}
