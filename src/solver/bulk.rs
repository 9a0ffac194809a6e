//! Assembly of the bulk (solid) residual and tangent into PETSc objects.
//!
//! The residual is `F(u) = f_int(u) - f_ext(u, t)`: internal forces of the elements this rank
//! owns (`solid::internal_force`), minus follower pressures on their faces and body forces, at the
//! full displacement (free dofs from the Newton iterate, constrained dofs from the load curves).
//! The tangent is `dF/du` restricted to the free dofs: `K_int - K_pressure` (the follower
//! pressure's tangent is nonsymmetric).
//!
//! Inverted elements do not stop assembly half-way (that would leave other ranks waiting in the
//! collective `VecAssembly`/`MatAssembly`): the element is skipped, assembly completes, and the
//! caller reduces the flag over ranks and reports a domain error on every rank together.

use nalgebra::DMatrix;

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{Error, Result};
use crate::fe::{quadrature::Rule2, FaceType};
use crate::petsc::{Matrix, PetscInt, Vector};
use crate::solid::{self, ElementGeometry};

/// A face carrying a follower pressure, on an element of this rank.
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
}

/// Where a residual or tangent evaluation found an inverted element.
#[derive(Clone, Debug)]
pub struct Inverted {
    pub element: usize,
    pub det: f64,
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
        let mut faces = Vec::new();
        for (load, p) in scene.pressures.iter().enumerate() {
            for f in p
                .faces
                .iter()
                .filter(|f| dofs.element_rank[f.element] == dofs.rank)
            {
                faces.push(LoadedFace {
                    nodes: mesh.face_nodes(*f),
                    kind: mesh.face_type(*f),
                    load,
                });
            }
        }
        let face_rules = crate::fe::FaceType::ALL
            .iter()
            .map(|&ft| (ft, ft.quadrature(ft.default_quadrature_degree())))
            .collect();
        Ok(Bulk {
            elements,
            faces,
            face_rules,
        })
    }

    /// The local elements and their geometry.
    pub fn elements(&self) -> &[(usize, ElementGeometry)] {
        &self.elements
    }

    fn face_rule(&self, ft: FaceType) -> &Rule2 {
        &self
            .face_rules
            .iter()
            .find(|(t, _)| *t == ft)
            .expect("a rule for every face type")
            .1
    }

    /// Adds this rank's contributions to `F(u)` into `f` (not zeroed, not assembled: the caller
    /// adds the interfaces' terms and assembles). `u` holds the displacement of every node this
    /// rank touches (`3 * node + c`).
    pub fn add_residual(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        t: f64,
        f: &mut Vector,
    ) -> Result<Option<Inverted>> {
        let mut inverted = None;
        let mut idx: Vec<PetscInt> = Vec::new();
        let mut fe = Vec::new();
        let mut ue = Vec::new();
        for (e, geom) in &self.elements {
            let nodes = scene.mesh.element_nodes(*e);
            gather_nodes(u, nodes, &mut ue);
            fe.resize(3 * nodes.len(), 0.0);
            let mat = &scene.materials[scene.mesh.body[*e]];
            if let Err(det) = solid::internal_force(geom, mat, &ue, &mut fe, None) {
                inverted.get_or_insert(Inverted { element: *e, det });
                continue;
            }
            self.subtract_body_forces(scene, *e, geom, t, &mut fe);
            dofs.element_dofs(nodes, &mut idx);
            f.set_values(&idx, &fe, true)?;
        }
        for face in &self.faces {
            let (x, p) = self.face_state(scene, face, u, t);
            fe.resize(3 * face.nodes.len(), 0.0);
            solid::follower_pressure(face.kind, self.face_rule(face.kind), &x, p, &mut fe, None);
            fe.iter_mut().for_each(|v| *v = -*v);
            dofs.element_dofs(&face.nodes, &mut idx);
            f.set_values(&idx, &fe, true)?;
        }
        Ok(inverted)
    }

    /// Adds the tangent `dF/du` (free dofs only) into `jac` (not zeroed, not assembled).
    pub fn add_jacobian(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        t: f64,
        jac: &mut Matrix,
    ) -> Result<Option<Inverted>> {
        let mut inverted = None;
        let mut idx: Vec<PetscInt> = Vec::new();
        let mut fe = Vec::new();
        let mut ue = Vec::new();
        let mut ke = DMatrix::zeros(0, 0);
        // The element blocks go straight into the stored rows (`petsc::OwnedRows`: the same
        // sums as `MatSetValues`, without its per-entry search).
        jac.with_owned_rows(|owned| {
            for (e, geom) in &self.elements {
                let nodes = scene.mesh.element_nodes(*e);
                gather_nodes(u, nodes, &mut ue);
                fe.resize(3 * nodes.len(), 0.0);
                let mat = &scene.materials[scene.mesh.body[*e]];
                if let Err(det) = solid::internal_force(geom, mat, &ue, &mut fe, Some(&mut ke)) {
                    inverted.get_or_insert(Inverted { element: *e, det });
                    continue;
                }
                dofs.element_dofs(nodes, &mut idx);
                // nalgebra is column-major; PETSc takes row-major. The element tangent is
                // symmetric but transpose anyway so a nonsymmetric law stays right.
                let rows = ke.transpose();
                owned.add(&idx, &idx, rows.as_slice())?;
            }
            Ok(())
        })?;
        for face in &self.faces {
            let (x, p) = self.face_state(scene, face, u, t);
            fe.resize(3 * face.nodes.len(), 0.0);
            solid::follower_pressure(
                face.kind,
                self.face_rule(face.kind),
                &x,
                p,
                &mut fe,
                Some(&mut ke),
            );
            if !scene.pressures[face.load].follower {
                continue;
            }
            // F = f_int - f_ext: the pressure's contribution to dF/du is -d f_ext / dx.
            let rows = -ke.transpose();
            dofs.element_dofs(&face.nodes, &mut idx);
            jac.add_values(&idx, &idx, rows.as_slice())?;
        }
        Ok(inverted)
    }

    /// `f_int - f_ext` of each local element at every dof, summed into `out` (indexed by dof
    /// `3 * node + c`); used for reactions at constrained dofs.
    pub fn nodal_forces(&self, scene: &Scene, u: &[f64], t: f64, out: &mut [f64]) {
        let mut fe = Vec::new();
        let mut ue = Vec::new();
        for (e, geom) in &self.elements {
            let nodes = scene.mesh.element_nodes(*e);
            gather_nodes(u, nodes, &mut ue);
            fe.resize(3 * nodes.len(), 0.0);
            let mat = &scene.materials[scene.mesh.body[*e]];
            if solid::internal_force(geom, mat, &ue, &mut fe, None).is_err() {
                continue;
            }
            self.subtract_body_forces(scene, *e, geom, t, &mut fe);
            scatter_add(out, nodes, &fe);
        }
        for face in &self.faces {
            let (x, p) = self.face_state(scene, face, u, t);
            fe.resize(3 * face.nodes.len(), 0.0);
            solid::follower_pressure(face.kind, self.face_rule(face.kind), &x, p, &mut fe, None);
            fe.iter_mut().for_each(|v| *v = -*v);
            scatter_add(out, &face.nodes, &fe);
        }
    }

    fn subtract_body_forces(
        &self,
        scene: &Scene,
        e: usize,
        geom: &ElementGeometry,
        t: f64,
        fe: &mut [f64],
    ) {
        // The consistent load is linear in b: sum the body's forces, integrate once, on the
        // stack (this runs for every element in every residual).
        let body = scene.mesh.body[e];
        let mut v = [0.0; 3];
        let mut any = false;
        for b in scene
            .body_forces
            .iter()
            .filter(|b| b.bodies.contains(&body))
        {
            let s = scene.curves[b.curve].eval(t);
            for (vc, bc) in v.iter_mut().zip(b.value) {
                *vc += bc * s;
            }
            any = true;
        }
        if !any {
            return;
        }
        let mut buffer = [0.0; 3 * solid::MAX_NODES];
        let fb = &mut buffer[..fe.len()];
        solid::body_force(geom, v, fb);
        fe.iter_mut().zip(fb.iter()).for_each(|(a, b)| *a -= b);
    }

    /// Coordinates of a loaded face (current for a follower load, reference for a dead load)
    /// and its pressure at load factor t.
    fn face_state(
        &self,
        scene: &Scene,
        face: &LoadedFace,
        u: &[f64],
        t: f64,
    ) -> (Vec<[f64; 3]>, f64) {
        let load = &scene.pressures[face.load];
        let s = if load.follower { 1.0 } else { 0.0 };
        let x = face
            .nodes
            .iter()
            .map(|&v| {
                let x0 = scene.mesh.coords[v];
                [
                    x0[0] + s * u[3 * v],
                    x0[1] + s * u[3 * v + 1],
                    x0[2] + s * u[3 * v + 2],
                ]
            })
            .collect();
        (x, load.value * scene.curves[load.curve].eval(t))
    }
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

fn scatter_add(out: &mut [f64], nodes: &[usize], fe: &[f64]) {
    for (a, &v) in nodes.iter().enumerate() {
        for c in 0..3 {
            out[3 * v + c] += fe[3 * a + c];
        }
    }
}
